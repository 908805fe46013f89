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

}  // namespace fetouch::app
