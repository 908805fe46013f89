// What a tetrahedral .vtu's regions share, for conformity checks (tests only): each triangular face
// with the regions of the tetrahedra that hold it, and the points that occur twice.
#pragma once

#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <vector>

namespace fetouch::testing {

using TetFaces = std::map<std::array<vtkIdType, 3>, std::vector<int>>;

// Every face of every tetrahedron (its sorted point ids) with the `region` values of the
// tetrahedra holding it: one for an outer face, two for an inner one.
inline TetFaces tet_faces(vtkUnstructuredGrid* grid, vtkDataArray* region) {
  TetFaces faces;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA) continue;
    vtkIdType n = 0;
    const vtkIdType* v = nullptr;
    grid->GetCellPoints(c, n, v);
    for (int f = 0; f < 4; ++f) {
      std::array<vtkIdType, 3> face{v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]};
      std::sort(face.begin(), face.end());
      faces[face].push_back(static_cast<int>(region->GetTuple1(c)));
    }
  }
  return faces;
}

// Points at exactly the place of an earlier point.
inline std::vector<vtkIdType> duplicated_points(vtkUnstructuredGrid* grid) {
  std::set<std::array<double, 3>> places;
  std::vector<vtkIdType> twice;
  for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p) {
    std::array<double, 3> x;
    grid->GetPoint(p, x.data());
    if (!places.insert(x).second) twice.push_back(p);
  }
  return twice;
}

}  // namespace fetouch::testing
