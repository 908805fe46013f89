// The tissue mesh as deal.II sees it: a Triangulation built from the scene's mesh (a Gmsh file or a
// generated primitive), the names of its boundary regions, and a few figures for summaries.
// This header includes no deal.II header, so the command line can use it cheaply; the Triangulation
// itself is built through tissue_mesh_builder.h.
#pragma once

#include <map>
#include <string>

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
};

// Builds the mesh of `spec` in deal.II and describes it. Throws std::runtime_error when the file cannot
// be read, when the cells do not suit spec.element (P needs tetrahedra, Q hexahedra), or when the mesh
// comes from a volume (that is meshed first, by `fetouch mesh`).
TissueMeshInfo inspect_tissue_mesh(const config::MeshSpec& spec);

}  // namespace fetouch::fem
