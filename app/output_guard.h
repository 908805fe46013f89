// Outputs that replace nothing by accident: outputs that would replace inputs are refused, and an
// output is written under a temporary name and renamed when complete.
//
// Outputs that would replace inputs. A command's --out may name a file the same command reads (the
// scene's mesh in the folder a solve writes, the recording a replay follows, the sweep a
// reconstruction reads); writing it would destroy the user's data, so the command refuses first.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace fetouch::app {

// Whether a and b are the same file: the same inode when both exist, else the same path once
// made absolute and normalised (symbolic links followed as far as they exist).
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// An input and what it is ("the scene", "the mesh", ...), for the message.
using NamedInput = std::pair<std::filesystem::path, std::string>;

// Throws std::invalid_argument naming both when one of `written` is one of `inputs`, or when an
// input lies in `folder` (if given) under a file name `written_in_folder` says the command writes.
void refuse_overwriting(const std::vector<std::filesystem::path>& written, const std::vector<NamedInput>& inputs,
                        const std::filesystem::path& folder = {},
                        const std::function<bool(const std::string& file_name)>& written_in_folder = {});

// Writes `path` whole or not at all: `write` fills a temporary file beside it (the same extension,
// so format-sniffing writers still see it), which then replaces `path` by a rename. If `write`
// throws, the temporary file is removed, `path` is left as it was and the exception goes on. A
// detached-header volume (.mhd, .nhdr: the header names its data file) is written in place.
void replace_when_written(const std::filesystem::path& path,
                          const std::function<void(const std::filesystem::path& temporary)>& write);
// `text` into `path` the same way; throws std::runtime_error naming the file if it cannot be written.
void write_text_file(const std::filesystem::path& path, const std::string& text);
// The name a file is written under until it is complete: DIR/STEM.partial.EXT.
std::filesystem::path partial_path(const std::filesystem::path& path);

}  // namespace fetouch::app
