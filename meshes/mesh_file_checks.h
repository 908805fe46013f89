// Checks on a mesh file before any reader sees it (issue 17), shared by the summary reader here and
// the solver's readers in fem/ (header only: fem does not link this module). Each throws
// std::runtime_error naming the file.
//  - Gmsh decides a file's format by its content and would run a .geo script (which can call the
//    shell): only a file whose first line is $MeshFormat goes to Gmsh.
//  - VTK's XML reader allocates what a .vtu declares before reading it: NumberOfPoints and
//    NumberOfCells are checked against a memory budget first.
//  - Both: a regular file (a FIFO or a device would block or never end) of at most 4 GB.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "meshes/msh_check.h"

namespace fetouch::meshes {

// Budgets: 5 * 10^7 points and 3 * 10^8 cells (about 10 GB once read), 4 GB of file.
constexpr double kMaxMeshPoints = 5e7, kMaxMeshCells = 3e8;
constexpr std::uintmax_t kMaxMeshFileBytes = 4ull << 30;
// The extent of a tissue mesh: 0.1 mm to 2 m along its longest side (metres; a mesh in
// millimetres is 1000 times too large).
constexpr double kMinMeshExtentM = 1e-4, kMaxMeshExtentM = 2;

inline void check_mesh_file(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw std::runtime_error(name + ": no such file");
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(name + ": not a regular file (a mesh is a .msh or .vtu file, not a folder, FIFO or device)");
  if (std::filesystem::file_size(path, error) > kMaxMeshFileBytes)
    throw std::runtime_error(name + ": over 4 GB; larger than any mesh Fetouch can solve on");
  // The first 64 KB: the first line of a .msh, the <Piece> counts of a .vtu (where VTK writes them).
  std::ifstream in(path, std::ios::binary);
  std::string text(65536, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (path.extension() == ".msh") {
    if (text.rfind("$MeshFormat", 0) != 0)
      throw std::runtime_error(name + ":1: not a Gmsh mesh (expected $MeshFormat on the first line)");
    check_msh_structure(path);  // Gmsh's reader trusts the file; it is checked line by line first
  } else if (path.extension() == ".vtu") {
    // A VTK file has no document type: entity declarations only serve to expand (the billion laughs).
    if (text.find("<!DOCTYPE") != std::string::npos || text.find("<!ENTITY") != std::string::npos)
      throw std::runtime_error(name + ": an XML document type or entity declaration; a VTK file has none");
    for (const auto& [key, limit] : {std::pair<const char*, double>{"NumberOfPoints=\"", kMaxMeshPoints},
                                     std::pair<const char*, double>{"NumberOfCells=\"", kMaxMeshCells}})
      for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
        const char* start = text.c_str() + at + std::char_traits<char>::length(key);
        char* end = nullptr;
        const double n = std::strtod(start, &end);
        if (end == start || *end != '"' || !(n >= 0 && n <= limit) || n != std::floor(n)) {
          const std::string value(start, std::min<std::size_t>(30, std::strcspn(start, "\"")));
          throw std::runtime_error(name + ": " + std::string(key, std::char_traits<char>::length(key) - 2) + " " + value +
                                   "; expected a whole number from 0 to " + std::to_string(static_cast<long long>(limit)) +
                                   " (the memory budget)");
        }
      }
  }
}

// Throws unless the bounding box [low, high] (m) has a plausible size for tissue.
inline void check_mesh_extent(const std::string& name, const double low[3], const double high[3]) {
  double longest = 0;
  for (int d = 0; d < 3; ++d) {
    const double side = high[d] - low[d];
    if (!std::isfinite(side) || !std::isfinite(low[d]))
      throw std::runtime_error(name + ": a coordinate is not a finite number");
    longest = std::max(longest, side);
  }
  if (!(longest >= kMinMeshExtentM && longest <= kMaxMeshExtentM)) {
    char shown[32];
    std::snprintf(shown, sizeof shown, "%g", longest);
    throw std::runtime_error(name + ": the mesh spans " + std::string(shown) +
                             " m; tissue spans 0.0001 to 2 m (coordinates are in metres: a mesh in millimetres is 1000 times too large)");
  }
}

}  // namespace fetouch::meshes
