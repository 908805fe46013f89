#include "imaging/separable_filter.h"

#include <algorithm>
#include <cmath>

namespace fetouch::imaging {

void convolve_axis(std::vector<float>& data, const std::array<int, 3>& n, int axis, const std::vector<double>& w,
                   Faces faces) {
  const int half = static_cast<int>(w.size() / 2);
  const std::size_t stride = axis == 0 ? 1 : axis == 1 ? std::size_t(n[0]) : std::size_t(n[0]) * n[1];
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  std::vector<float> line(n[axis]);
  for (int p = 0; p < n[a2]; ++p)
    for (int q = 0; q < n[a1]; ++q) {
      std::array<int, 3> start{0, 0, 0};
      start[a1] = q, start[a2] = p;
      const std::size_t base = (std::size_t(start[2]) * n[1] + start[1]) * n[0] + start[0];
      for (int i = 0; i < n[axis]; ++i) line[i] = data[base + i * stride];
      for (int i = 0; i < n[axis]; ++i) {
        double sum = 0, weight = 0;
        for (int k = -half; k <= half; ++k) {
          int at = i + k;
          if (faces == Faces::periodic) {
            at = ((at % n[axis]) + n[axis]) % n[axis];
          } else if (at < 0 || at >= n[axis]) {
            continue;
          }
          sum += w[k + half] * line[at], weight += w[k + half];
        }
        data[base + i * stride] = static_cast<float>(faces == Faces::periodic ? sum : sum / weight);
      }
    }
}

std::vector<double> gaussian_kernel(double sigma) {
  const int half = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<double> w(2 * half + 1);
  double sum = 0;
  for (int k = -half; k <= half; ++k) sum += w[k + half] = std::exp(-0.5 * k * k / (sigma * sigma));
  for (double& v : w) v /= sum;
  return w;
}

}  // namespace fetouch::imaging
