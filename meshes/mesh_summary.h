// What a mesh file holds: node and element counts by type, its physical groups and its bounds.
// Gmsh .msh files are read through the Gmsh API, .vtu files through VTK. Coordinates are in metres.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace fetouch::meshes {

struct PhysicalGroup {
  int dimension = 0;  // 2: a surface region (boundary conditions, cavity), 3: a volume region
  int tag = 0;
  std::string name;
};

struct MeshSummary {
  std::string format;  // "Gmsh 4.1", "VTK unstructured grid"
  long nodes = 0;
  std::map<std::string, long> elements;  // "tetrahedron", "triangle", "hexahedron", ...
  std::vector<PhysicalGroup> physical_groups;
  std::array<double, 3> min_m{0, 0, 0};
  std::array<double, 3> max_m{0, 0, 0};

  long count(const std::string& element_type) const;
  bool has_group(const std::string& name) const;
};

// Throws std::runtime_error naming the file and the problem.
MeshSummary read_mesh_summary(const std::filesystem::path& path);

}  // namespace fetouch::meshes
