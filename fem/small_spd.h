// A small symmetric positive semi-definite system G x = b: the Galerkin matrix B'A B of a few dozen
// directions (the compliance's span, a deflated CG's recycled directions). Solved by a Cholesky
// factorisation of G scaled to a unit diagonal and pivoted on the largest remaining diagonal; a
// direction whose pivot falls under `drop` (one the others already span to about half the digits
// of 1 / drop) is left out, its coefficient 0. Directions kept from earlier solves may so have become
// dependent on the others without spoiling the rest.
#pragma once

#include <vector>

namespace fetouch::fem {

class SmallSpd {
 public:
  // G is size x size, row-major, symmetric. False when a diagonal entry is not positive (the
  // operator is not positive definite there); nothing is then usable.
  bool factorise(const std::vector<double>& g, unsigned int size, double drop = 1e-12);
  unsigned int size() const { return size_; }
  unsigned int rank() const { return rank_; }  // the directions kept
  // x = G^-1 b over the kept directions (0 on the others); b and x of length size().
  void solve(const double* b, double* x) const;

 private:
  unsigned int size_ = 0, rank_ = 0;
  std::vector<double> l_;              // the scaled matrix's factor, in pivot order (size x size)
  std::vector<double> scale_;          // 1 / sqrt(G_aa)
  std::vector<unsigned int> order_;    // the pivot order
  mutable std::vector<double> y_;
};

}  // namespace fetouch::fem
