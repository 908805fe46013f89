// The index of the voxel holding a volume's largest value (where a test put its marker).
#pragma once

#include <array>
#include <cstddef>

#include "imaging/phantom.h"

namespace fetouch::testing {

inline std::array<int, 3> brightest_voxel(const imaging::Volume<float>& v) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < v.data.size(); ++i)
    if (v.data[i] > v.data[best]) best = i;
  const int nx = v.dimensions[0], ny = v.dimensions[1];
  return {static_cast<int>(best % nx), static_cast<int>(best / nx % ny), static_cast<int>(best / nx / ny)};
}

}  // namespace fetouch::testing
