// TangentSystem's products with K (tangent_system.h): one column, or several in one pass over the
// matrix, on the CSR arrays that are assembled and factorised.
#include "fem/tangent_system.h"

#include <algorithm>

namespace fetouch::fem {

namespace {
// y[j] = A x[j], j < M, in one pass over A (CSR): M sums a row, held in registers.
template <int M>
void multiply_pass(int n, const int* row_start, const int* columns, const double* values, const double* const* x,
                   double* const* y) {
  for (int i = 0; i < n; ++i) {
    double sum[M] = {};
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const double v = values[k];
      const int c = columns[k];
      for (int j = 0; j < M; ++j) sum[j] += v * x[j][c];
    }
    for (int j = 0; j < M; ++j) y[j][i] = sum[j];
  }
}
}  // namespace

void TangentSystem::multiply(const double* values, const double* x, double* y) const {
  multiply_pass<1>(static_cast<int>(rows()), row_start_.data(), columns_.data(), values, &x, &y);
}

void TangentSystem::multiply_columns(const double* const* x, double* const* y, int columns) const {
  const int n = static_cast<int>(rows());
  const int* rs = row_start_.data();
  const int* cs = columns_.data();
  const double* v = values_.data();
  for (int first = 0; first < columns; first += 8) {
    const double* const* xs = x + first;
    double* const* ys = y + first;
    switch (std::min(8, columns - first)) {
      case 1: multiply_pass<1>(n, rs, cs, v, xs, ys); break;
      case 2: multiply_pass<2>(n, rs, cs, v, xs, ys); break;
      case 3: multiply_pass<3>(n, rs, cs, v, xs, ys); break;
      case 4: multiply_pass<4>(n, rs, cs, v, xs, ys); break;
      case 5: multiply_pass<5>(n, rs, cs, v, xs, ys); break;
      case 6: multiply_pass<6>(n, rs, cs, v, xs, ys); break;
      case 7: multiply_pass<7>(n, rs, cs, v, xs, ys); break;
      default: multiply_pass<8>(n, rs, cs, v, xs, ys); break;
    }
  }
}

}  // namespace fetouch::fem
