// The linear systems of a solve: the supports (prescribed displacements per component on boundary
// regions) as constraints, the tangent's sparsity (free-free couplings and the diagonal of
// constrained dofs), the sparse tangent (tangent_system.h: CG on a stale factorisation, or AMG) plus
// an optional dense rank-one part c g g' (a fluid cavity's), and the time each phase took.
#pragma once

#include <deal.II/base/function.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/vector.h>

#include <array>
#include <functional>
#include <stdexcept>
#include <vector>

#include "fem/discretisation.h"
#include "fem/tangent_system.h"

namespace fetouch::fem {

using Field = std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&)>;

// scale * g(x) as a deal.II Function (interpolation, error norms); keeps a reference to the field.
class ScaledField : public dealii::Function<3> {
 public:
  ScaledField(const Field& field, double scale) : dealii::Function<3>(3), field_(field), scale_(scale) {}
  double value(const dealii::Point<3>& p, const unsigned int component) const override {
    return scale_ * field_(p)[component];
  }

 private:
  const Field& field_;
  double scale_;
};

// u = lambda g(x) on the selected components of a boundary region.
struct Support {
  unsigned int boundary;
  std::array<bool, 3> components;
  Field field;
};

class LinearSystem {
 public:
  LinearSystem(const Discretisation& discretisation, MPI_Comm comm);

  // Constraints and sparsity for these supports (throws std::invalid_argument for a boundary id no
  // face has); the tangent's values are then stale.
  void set_up(const std::vector<Support>& supports, TangentSystem::Method method);
  // u := factor g(x) on the supports' components: the supports given to set_up (their g(x) is kept
  // from the first call).
  void apply_supports(const std::vector<Support>& supports, double factor, dealii::Vector<double>& u) const;

  const dealii::AffineConstraints<double>& constraints() const { return constraints_; }
  const std::vector<bool>& constrained() const { return constrained_; }
  TangentSystem& tangent() { return tangent_; }
  const TangentSystem& tangent() const { return tangent_; }
  int position(int row, int column) const { return tangent_.position(row, column); }
  // Where each cell matrix entry (i, j) of cell k goes in the tangent's value array, at [i n + j];
  // -1 where the row or the column is constrained. Only for the cells this rank assembles
  // (Discretisation::my_cells), and only after build_cell_scatter(): a loop over cells calls it
  // once before it starts (before its threads run).
  const int* cell_scatter(unsigned int k) const {
    const int slot = d_.my_slot[k];
    if (slot < 0 || std::size_t(slot) * scatter_stride_ >= scatter_.size())
      throw std::logic_error("a cell matrix of a cell another rank assembles, or before build_cell_scatter()");
    return &scatter_[std::size_t(slot) * scatter_stride_];
  }
  void build_cell_scatter() const;
  // Counts set_up() calls: positions in the tangent's value array found under one revision hold
  // until the next.
  int pattern_revision() const { return pattern_revision_; }

  // The rank-one part (c = 0: none); g must outlive the next solves.
  void set_rank_one(double c, const dealii::Vector<double>* g);
  double rank_one_c() const { return rank_one_c_; }
  const dealii::Vector<double>* rank_one_g() const { return rank_one_g_; }
  // x = K^-1 rhs to a relative residual `tolerance` (x holds the initial guess unless zero_guess),
  // constraints distributed.
  void solve(const dealii::Vector<double>& rhs, dealii::Vector<double>& x, double tolerance, bool zero_guess);
  // y[k] = K x[k] (K with the rank-one part) for `count` columns of rows() entries each, given by
  // their starts; K is read once per eight of them (the compliance's columns).
  void multiply(const double* const* x, double* const* y, int count) const;
  // X = P^-1 B, `columns` right-hand sides (column-major), P the factorisation.
  void apply_factorisation(const double* b, double* x, int columns);
  // w = (P + c g g')^-1 g, g the rank-one part's (set_rank_one).
  void apply_factorisation_to_rank_one_g(dealii::Vector<double>& w);

  // The tangent was assembled anew (drops y).
  void tangent_changed() { y_current_ = false; }
  // An assembly ran: the rank-one term's g may have moved with the state (drops P^-1 g).
  void assembled() { tangent_.rank_one_moved(); }

  struct Times {
    double factorisation_s = 0, solve_s = 0;
    int linear_iterations = 0;
  };
  Times times;  // accumulated; the caller resets it

 private:
  void account(const TangentSystem::SolveStats& stats);
  const Discretisation& d_;
  dealii::AffineConstraints<double> constraints_;
  std::vector<bool> constrained_;
  // Built by build_cell_scatter(), for this rank's cells only (d_.my_cells: all of them on one
  // rank), in their order (Discretisation::my_slot), scatter_stride_ ints a cell.
  mutable std::vector<int> scatter_;
  mutable std::size_t scatter_stride_ = 0;
  // g(x) at each support's dofs, kept from the first apply_supports after set_up.
  mutable std::vector<std::vector<std::pair<dealii::types::global_dof_index, double>>> support_values_;
  int pattern_revision_ = 0;
  TangentSystem tangent_;
  double rank_one_c_ = 0;
  const dealii::Vector<double>* rank_one_g_ = nullptr;
  dealii::Vector<double> y_;  // K_s^-1 g, where the tangent's solve leaves the rank-one part here
  bool y_current_ = false;
};

}  // namespace fetouch::fem
