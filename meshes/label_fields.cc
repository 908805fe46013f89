#include "meshes/label_fields.h"

#include <cmath>

namespace fetouch::meshes {

void grade(GridField& s, double grading) {
  const auto& n = s.n;
  const auto sweep = [&](int sign) {
    const long nx = n[0], ny = n[1], nz = n[2];
    for (long kk = 0; kk < nz; ++kk)
      for (long jj = 0; jj < ny; ++jj)
        for (long ii = 0; ii < nx; ++ii) {
          const long i = sign > 0 ? ii : nx - 1 - ii, j = sign > 0 ? jj : ny - 1 - jj, k = sign > 0 ? kk : nz - 1 - kk;
          float& here = s.v[std::size_t((k * ny + j) * nx + i)];
          // The neighbours already swept: the 13 before this voxel in raster order (mirrored going back).
          for (int dk = -1; dk <= 0; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di) {
                if (dk == 0 && (dj > 0 || (dj == 0 && di >= 0))) continue;
                const long a = i + sign * di, b = j + sign * dj, c = k + sign * dk;
                if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
                const double d = std::sqrt(di * di * s.h[0] * s.h[0] + dj * dj * s.h[1] * s.h[1] + dk * dk * s.h[2] * s.h[2]);
                here = std::min(here, static_cast<float>(s.at(a, b, c) + grading * d));
              }
        }
  };
  sweep(+1);
  sweep(-1);
}

std::vector<double> volume_biases(const std::map<std::pair<int, int>, double>& between, const std::vector<double>& missing,
                                  double slope, std::vector<double> bias) {
  const std::size_t R = missing.size() - 1;  // the regions, the background left out
  std::vector<double> L(R * R, 0.0), rhs(R, 0.0);
  for (const auto& [pair, a] : between) {
    const auto [r, q] = pair;
    if (r > 0) L[std::size_t(r - 1) * R + std::size_t(r - 1)] += a;
    if (q > 0) L[std::size_t(q - 1) * R + std::size_t(q - 1)] += a;
    if (r > 0 && q > 0) L[std::size_t(r - 1) * R + std::size_t(q - 1)] -= a, L[std::size_t(q - 1) * R + std::size_t(r - 1)] -= a;
  }
  for (std::size_t r = 0; r < R; ++r) {
    rhs[r] = missing[r + 1] * slope;
    if (L[r * R + r] <= 0) L[r * R + r] = 1, rhs[r] = 0;  // a region without a surface
  }
  for (std::size_t k = 0; k < R; ++k)  // symmetric positive definite: no pivoting
    for (std::size_t i = k + 1; i < R; ++i) {
      const double f = L[i * R + k] / L[k * R + k];
      for (std::size_t j = k; j < R; ++j) L[i * R + j] -= f * L[k * R + j];
      rhs[i] -= f * rhs[k];
    }
  for (std::size_t k = R; k-- > 0;) {
    double x = rhs[k];
    for (std::size_t j = k + 1; j < R; ++j) x -= L[k * R + j] * bias[j + 1];
    bias[k + 1] = std::clamp(x / L[k * R + k], -0.25, 0.25);
  }
  return bias;
}

}  // namespace fetouch::meshes
