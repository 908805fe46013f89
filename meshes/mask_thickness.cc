// The thickness of a segmentation (meshes/mask_thickness.h).
#include "meshes/mask_thickness.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace fetouch::meshes {

double thickest_part_mm(const MaskVolume& mask) {
  const auto& n = mask.dimensions;
  const auto& h = mask.spacing_mm;
  const std::size_t count = std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]);
  if (count == 0 || mask.data.size() != count) return 0;
  const float far = std::numeric_limits<float>::max();
  std::vector<float> d(count);
  for (std::size_t i = 0; i < count; ++i) d[i] = mask.data[i] ? far : 0.f;
  // The 13 neighbours before a voxel in scan order (and, mirrored, the 13 after it).
  struct Step {
    int i, j, k;
    float length;
  };
  std::vector<Step> before;
  for (int k = -1; k <= 0; ++k)
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i)
        if (k < 0 || j < 0 || (j == 0 && i < 0))
          before.push_back({i, j, k, static_cast<float>(std::sqrt(i * i * h[0] * h[0] + j * j * h[1] * h[1] + k * k * h[2] * h[2]))});
  const auto pass = [&](int sign) {
    const int k0 = sign > 0 ? 0 : n[2] - 1, j0 = sign > 0 ? 0 : n[1] - 1, i0 = sign > 0 ? 0 : n[0] - 1;
    for (int k = k0; k >= 0 && k < n[2]; k += sign)
      for (int j = j0; j >= 0 && j < n[1]; j += sign)
        for (int i = i0; i >= 0 && i < n[0]; i += sign) {
          const std::size_t at = (std::size_t(k) * n[1] + j) * n[0] + i;
          if (d[at] == 0.f) continue;
          for (const Step& s : before) {
            const int a = i + sign * s.i, b = j + sign * s.j, c = k + sign * s.k;
            // Outside the volume counts as outside the segmentation.
            const float there = a < 0 || b < 0 || c < 0 || a >= n[0] || b >= n[1] || c >= n[2]
                                    ? 0.f
                                    : d[(std::size_t(c) * n[1] + b) * n[0] + a];
            d[at] = std::min(d[at], there + s.length);
          }
        }
  };
  pass(+1);
  pass(-1);
  const float deepest = *std::max_element(d.begin(), d.end());
  if (deepest == 0.f) return 0;
  // A voxel's distance runs to the centre of the nearest voxel outside: the ball reaches half a
  // voxel less far.
  return 2 * double(deepest) - std::min({h[0], h[1], h[2]});
}

}  // namespace fetouch::meshes
