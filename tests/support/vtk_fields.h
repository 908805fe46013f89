// Reading fields back from the VTK files fetouch writes (tests only).
#pragma once

#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>

namespace fetouch::testing {

// The largest length of a 3-component point array (-1 when the grid has no such array).
inline double largest_point_vector(vtkUnstructuredGrid* grid, const char* name = "displacement") {
  vtkDataArray* u = grid->GetPointData()->GetArray(name);
  if (!u) return -1;
  double largest = 0;
  for (vtkIdType i = 0; i < u->GetNumberOfTuples(); ++i) {
    const double* d = u->GetTuple3(i);
    largest = std::max(largest, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
  }
  return largest;
}

}  // namespace fetouch::testing
