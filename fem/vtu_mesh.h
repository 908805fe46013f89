// Tissue meshes from VTK's XML unstructured grids (.vtu), the format ParaView, VTK pipelines and
// `fetouch mesh` write. Convention:
//   - volume cells: tetrahedra (VTK_TETRA) or hexahedra (VTK_HEXAHEDRON), not mixed; an optional
//     integer cell array `material_id` gives each its region (default 0);
//   - boundary regions: triangles or quadrilaterals in the same grid, each coinciding with a face of
//     a volume cell, tagged by the integer cell array `boundary_id`; an optional string field array
//     `boundary_names` names ids 0, 1, ... (otherwise the regions are named `boundary_<id>`), and
//     `region_names` material ids 0, 1, ... (`fetouch mesh --regions` writes both);
//   - points in metres; other cells (vertices, lines) are ignored.
// Tetrahedra of negative orientation are reordered; a hexahedron's VTK vertex order becomes
// deal.II's lexicographic one.
#pragma once

#include <deal.II/grid/tria.h>

#include <map>
#include <string>

namespace fetouch::fem {

// Reads `path` into `tria` and returns the boundary regions' names with their ids. Throws
// std::runtime_error naming the file and what is wrong (unreadable, no volume cells, mixed cells,
// a boundary cell that is not a face of the mesh).
// `region_names`, if given, receives the names of the material ids that `region_names` names.
std::map<std::string, unsigned int> read_vtu_mesh(const std::string& path, dealii::Triangulation<3>& tria,
                                                  std::map<unsigned int, std::string>* region_names = nullptr);

}  // namespace fetouch::fem
