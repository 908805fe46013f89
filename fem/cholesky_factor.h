// A sparse Cholesky factorisation K = L L' of a symmetric positive definite matrix (CHOLMOD,
// supernodal, called directly rather than through PETSc so that a factorisation can run on a worker
// thread while the solver thread solves with another one: each factor owns its CHOLMOD workspace).
//
// The pattern is given once in compressed sparse rows with both triangles (a symmetric CSR is also
// its own CSC; CHOLMOD reads the upper triangle). The fill-reducing ordering and the symbolic
// analysis are done at construction; factorise() is the numeric phase only.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

namespace fetouch::fem {

class CholeskyFactor {
 public:
  CholeskyFactor(int rows, const int* row_start, const int* columns);
  ~CholeskyFactor();
  CholeskyFactor(const CholeskyFactor&) = delete;
  CholeskyFactor& operator=(const CholeskyFactor&) = delete;

  // The numeric factorisation of `values` (in the pattern's order). False when K is not positive
  // definite (a tangent past a limit point): the factor is then unusable.
  bool factorise(const double* values);
  bool valid() const { return valid_; }
  // X = K^-1 B for `columns` right-hand sides, column-major (rows x columns).
  void solve(const double* b, double* x, int columns = 1);
  // The same with the factor's entries rounded to single precision (kept beside the double ones
  // when single_copy is set before factorise): half the bytes to read, for a preconditioner.
  void solve_single(const double* b, double* x, int columns = 1);
  bool single_copy = false;
  // Entries of L as the symbolic analysis laid it out (supernodal: the dense blocks' entries).
  std::size_t factor_entries() const;
  bool has_single() const { return valid_ && !single_.empty(); }
  // Floating-point operations of one numeric factorisation, by the symbolic analysis.
  double flops() const { return flops_; }

 private:
  struct Cholmod;
  std::unique_ptr<Cholmod> c_;
  bool valid_ = false;
  double flops_ = 0;
  std::vector<float> single_;
  std::vector<float> single_work_;
  std::size_t widest_ = 0;  // rows of the largest supernode
};

}  // namespace fetouch::fem
