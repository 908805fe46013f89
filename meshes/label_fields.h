// The conforming mesher's fields on the label map's padded voxel grid (meshes/labeled_mesher.h):
// a scalar field looked up trilinearly (the blurred region indicators, the sizing field), the
// sizing field's grading, and the indicator biases that give each region its voxels' volume. No
// CGAL here: the two translation units that include it stay the only ones.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

namespace fetouch::meshes {

// A scalar field on the padded grid, x fastest, looked up trilinearly at a point of the grid's
// frame (millimetres from the first padded voxel's centre along the index axes).
struct GridField {
  std::array<int, 3> n{};
  std::array<double, 3> h{};
  std::vector<float> v;
  float at(long i, long j, long k) const { return v[std::size_t((k * n[1] + j) * n[0] + i)]; }
  // The 8 voxels around a point and their trilinear weights (the same for every field of a grid).
  struct Stencil {
    std::array<std::size_t, 8> index;
    std::array<double, 8> weight;
  };
  Stencil stencil(double x, double y, double z) const {
    const double t[3] = {x / h[0], y / h[1], z / h[2]};
    long i0[3];
    double f[3];
    for (int c = 0; c < 3; ++c) {
      const double clamped = std::clamp(t[c], 0.0, double(n[c] - 1) - 1e-9);
      i0[c] = static_cast<long>(clamped);
      f[c] = clamped - double(i0[c]);
    }
    Stencil s{};
    int corner = 0;
    for (int dk = 0; dk < 2; ++dk)
      for (int dj = 0; dj < 2; ++dj)
        for (int di = 0; di < 2; ++di, ++corner) {
          const long i = std::min<long>(i0[0] + di, n[0] - 1), j = std::min<long>(i0[1] + dj, n[1] - 1),
                     k = std::min<long>(i0[2] + dk, n[2] - 1);
          s.index[std::size_t(corner)] = std::size_t((k * n[1] + j) * n[0] + i);
          s.weight[std::size_t(corner)] = (di ? f[0] : 1 - f[0]) * (dj ? f[1] : 1 - f[1]) * (dk ? f[2] : 1 - f[2]);
        }
    return s;
  }
  double at(const Stencil& s) const {
    double sum = 0;
    for (std::size_t c = 0; c < 8; ++c) sum += s.weight[c] * v[s.index[c]];
    return sum;
  }
  double operator()(double x, double y, double z) const { return at(stencil(x, y, z)); }
};

// s = min(s, s(neighbour) + grading * distance) over the 26 neighbours, by a forward and a backward
// raster sweep (a chamfer distance transform with the sizes as its sources).
void grade(GridField& s, double grading);

// The biases (level offsets) of the region indicators that give every region its voxels' volume,
// to first order: a surface between regions r and q moves by (b_r - b_q) / slope (the slope at
// which two blurred indicators part across a step), so region r gains sum_q A_rq (b_r - b_q) /
// slope: a graph Laplacian over the regions, the background's (index 0) bias held where it is.
// `between`: the area between two regions (lower index first; 0 the background), mm^2; `missing`:
// each region's voxels' volume less its mesh's, mm^3. Each bias is clamped to +-0.25; a region
// with no surface gets 0. `bias` is the previous one (its entry 0 is kept).
std::vector<double> volume_biases(const std::map<std::pair<int, int>, double>& between, const std::vector<double>& missing,
                                  double slope, std::vector<double> bias);

}  // namespace fetouch::meshes
