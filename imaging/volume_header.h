// MetaImage and NRRD text headers: their keys, and refusing files whose data is not what the header
// says (compressed data that inflates to another size, raw data cut short) before VTK's readers see
// them. The checks throw std::runtime_error naming the file, the size promised and the size held.
#pragma once

#include <filesystem>
#include <ios>
#include <map>
#include <string>

namespace fetouch::imaging {

// A text header's "key = value" (MetaImage, separator '=') or "key: value" (NRRD, ':') lines, up to
// the data: the line ElementDataFile (MetaImage) or an empty line (NRRD). `end`, if given, receives
// the header's size in bytes; `lines`, if given, each key's line number (1: the first line).
std::map<std::string, std::string> text_header(const std::filesystem::path& path, char separator,
                                               std::streamoff* end = nullptr,
                                               std::map<std::string, int>* lines = nullptr);

void check_metaimage_size(const std::filesystem::path& path);  // .mha, .mhd + data file
void check_nrrd_size(const std::filesystem::path& path);       // .nrrd, .nhdr + data file

}  // namespace fetouch::imaging
