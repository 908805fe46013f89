// VTK's error text folded into one line for a user: VTK writes "ERROR: In ./IO/XML/vtkXMLReader.cxx,
// line 521\nvtkXMLUnstructuredGridReader (0x55ad...): Error parsing input file." and the source
// file, line and object address mean nothing to someone whose file was refused. Header only, plain
// strings (meshes/ includes it for its .vtu reader too).
#pragma once

#include <cctype>
#include <string>

namespace fetouch::imaging {

inline std::string vtk_message(const std::string& raw) {
  std::string out;
  std::size_t at = 0;
  while (at < raw.size()) {
    std::size_t end = raw.find('\n', at);
    if (end == std::string::npos) end = raw.size();
    std::string line = raw.substr(at, end - at);
    at = end + 1;
    if (line.rfind("ERROR: In ", 0) == 0 || line.rfind("Warning: In ", 0) == 0) continue;  // VTK's source file and line
    const std::size_t object = line.find(" (0x");  // "vtkSomeReader (0x55ad...): text"
    const std::size_t colon = object == std::string::npos ? std::string::npos : line.find("): ", object);
    if (colon != std::string::npos) line = line.substr(colon + 3);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    if (line.empty()) continue;
    out += (out.empty() ? "" : "; ") + line;
  }
  if (out.size() > 300) out = out.substr(0, 297) + "...";
  return out.empty() ? "VTK could not read it" : out;
}

}  // namespace fetouch::imaging
