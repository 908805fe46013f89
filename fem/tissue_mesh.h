// The tissue mesh as deal.II sees it: a Triangulation built from the scene's mesh (a Gmsh file or a
// generated primitive), the names of its boundary regions, and a few figures for summaries.
// This header includes no deal.II header, so the command line can use it cheaply; the Triangulation
// itself is built through tissue_mesh_builder.h.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "config/diagnostics.h"
#include "config/scene.h"

namespace fetouch::fem {

struct TissueMeshInfo {
  unsigned int cells = 0;
  unsigned int vertices = 0;
  bool simplex = false;       // tetrahedra (P elements) or hexahedra (Q elements)
  double volume_m3 = 0;
  double min_diameter_m = 0;
  double max_diameter_m = 0;
  std::map<std::string, unsigned int> boundary_ids;  // named boundary regions
  // The volume regions, by material id: a Gmsh mesh's volume physical groups (named), a .vtu's
  // material ids, one region (id 0) for a generated mesh.
  struct Region {
    unsigned int material_id = 0;
    std::string name;  // the physical group's name; empty if it has none
    unsigned int cells = 0;
    double volume_m3 = 0;
  };
  std::vector<Region> regions;
};

// The scene's material of each region of the mesh: an index into scene.materials, or -1 for
// scene.material. `problems` has an error for every `materials:` entry that names no region of the
// mesh and every region that has no material (only `materials:` given), at the scene's file and line.
struct RegionMaterials {
  std::map<unsigned int, int> of_region;  // material id -> index
  std::vector<config::Diagnostic> problems;
};
RegionMaterials assign_region_materials(const config::Scene& scene, const TissueMeshInfo& mesh);
// The region named `name`, or whose material id `name` writes; nullptr if none.
const TissueMeshInfo::Region* find_region(const TissueMeshInfo& mesh, const std::string& name);
// "fluid (id 2)" or "id 2".
std::string describe_region(const TissueMeshInfo::Region& region);

// Builds the mesh of `spec` in deal.II and describes it. Throws std::runtime_error when the file cannot
// be read, when the cells do not suit spec.element (P needs tetrahedra, Q hexahedra), or when the mesh
// comes from a volume (that is meshed first, by `fetouch mesh`).
TissueMeshInfo inspect_tissue_mesh(const config::MeshSpec& spec);

}  // namespace fetouch::fem
