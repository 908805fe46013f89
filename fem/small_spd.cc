#include "fem/small_spd.h"

#include <cmath>
#include <utility>

namespace fetouch::fem {

bool SmallSpd::factorise(const std::vector<double>& g, unsigned int size, double drop) {
  size_ = size, rank_ = 0;
  scale_.assign(size, 0.0);
  for (unsigned int a = 0; a < size; ++a) {
    if (!(g[a * size + a] > 0)) return false;
    scale_[a] = 1 / std::sqrt(g[a * size + a]);
  }
  // l(a, b) of the scaled matrix, indexed by the original directions; overwritten by the factor.
  l_.resize(std::size_t(size) * size);
  for (unsigned int a = 0; a < size; ++a)
    for (unsigned int b = 0; b < size; ++b) l_[a * size + b] = scale_[a] * g[a * size + b] * scale_[b];
  const auto l = [&](unsigned int a, unsigned int b) -> double& { return l_[std::size_t(a) * size + b]; };
  order_.resize(size);
  for (unsigned int a = 0; a < size; ++a) order_[a] = a;
  for (; rank_ < size; ++rank_) {
    unsigned int pivot = rank_;
    for (unsigned int a = rank_ + 1; a < size; ++a)
      if (l(order_[a], order_[a]) > l(order_[pivot], order_[pivot])) pivot = a;
    std::swap(order_[rank_], order_[pivot]);
    const unsigned int p = order_[rank_];
    if (!(l(p, p) > drop)) break;
    const double root = std::sqrt(l(p, p));
    l(p, p) = root;
    for (unsigned int a = rank_ + 1; a < size; ++a) l(order_[a], p) /= root;
    for (unsigned int a = rank_ + 1; a < size; ++a)
      for (unsigned int b = rank_ + 1; b <= a; ++b) {
        const unsigned int i = order_[a], j = order_[b];
        l(i, j) -= l(i, p) * l(j, p);
        l(j, i) = l(i, j);
      }
  }
  return true;
}

void SmallSpd::solve(const double* b, double* x) const {
  const unsigned int n = size_;
  const auto l = [&](unsigned int a, unsigned int c) { return l_[std::size_t(a) * n + c]; };
  y_.assign(rank_, 0.0);
  for (unsigned int i = 0; i < rank_; ++i) {  // L y = S b
    double sum = scale_[order_[i]] * b[order_[i]];
    for (unsigned int j = 0; j < i; ++j) sum -= l(order_[i], order_[j]) * y_[j];
    y_[i] = sum / l(order_[i], order_[i]);
  }
  for (unsigned int i = rank_; i-- > 0;) {  // L' v = y, then x = S v
    double sum = y_[i];
    for (unsigned int j = i + 1; j < rank_; ++j) sum -= l(order_[j], order_[i]) * y_[j];
    y_[i] = sum / l(order_[i], order_[i]);
  }
  for (unsigned int a = 0; a < n; ++a) x[a] = 0;
  for (unsigned int i = 0; i < rank_; ++i) x[order_[i]] = scale_[order_[i]] * y_[i];
}

}  // namespace fetouch::fem
