#include "fem/linear_system.h"

#include <numeric>

#include <deal.II/base/function.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/component_mask.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/numerics/vector_tools.h>

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace fetouch::fem {

using namespace dealii;

namespace {

ComponentMask mask(const std::array<bool, 3>& components) { return ComponentMask({components[0], components[1], components[2]}); }

}  // namespace

LinearSystem::LinearSystem(const Discretisation& discretisation, MPI_Comm comm) : d_(discretisation), tangent_(comm) {}

void LinearSystem::set_up(const std::vector<Support>& supports, TangentSystem::Method method) {
  constraints_.clear();
  std::set<types::boundary_id> present;
  for (const auto& face : d_.tria.active_face_iterators())
    if (face->at_boundary()) present.insert(face->boundary_id());
  for (const Support& s : supports)
    if (!present.count(s.boundary))
      throw std::invalid_argument("prescribed displacement: no boundary face has id " + std::to_string(s.boundary));
  for (const Support& s : supports)
    VectorTools::interpolate_boundary_values(*d_.mapping, d_.dof, s.boundary, Functions::ZeroFunction<3>(3), constraints_,
                                             mask(s.components));
  constraints_.close();
  const types::global_dof_index n = d_.dof.n_dofs();
  constrained_.assign(n, false);
  for (types::global_dof_index i = 0; i < n; ++i) constrained_[i] = constraints_.is_constrained(i);
  // Couplings of free dofs, and the diagonal of constrained ones.
  DynamicSparsityPattern dsp(n);
  DoFTools::make_sparsity_pattern(d_.dof, dsp);
  std::vector<int> row_start{0}, columns;
  for (types::global_dof_index i = 0; i < n; ++i) {
    for (auto entry = dsp.begin(i); entry != dsp.end(i); ++entry) {
      const types::global_dof_index j = entry->column();
      if (i == j || (!constrained_[i] && !constrained_[j])) columns.push_back(static_cast<int>(j));
    }
    row_start.push_back(static_cast<int>(columns.size()));
  }
  const Discretisation::NearNullSpace space =
      method == TangentSystem::Method::amg ? d_.near_null_space(constrained_) : Discretisation::NearNullSpace{};
  tangent_.set_pattern(std::move(row_start), std::move(columns), method, d_.owned_begin, d_.owned_end, space.modes,
                       space.node_block);
  y_current_ = false;
  scatter_.clear();
  support_values_.clear();
  ++pattern_revision_;
}

// n x n ints a cell (576 bytes for P1: 287 MB at 522,240 cells), so only for this rank's cells.
void LinearSystem::build_cell_scatter() const {
  const Discretisation::Cells& c = d_.cells();
  const unsigned int n = c.n;
  const std::vector<unsigned int>& mine = d_.my_cells;
  if (scatter_stride_ == std::size_t(n) * n && scatter_.size() == mine.size() * n * n) return;  // once per set_up
  scatter_stride_ = std::size_t(n) * n;
  scatter_.resize(mine.size() * n * n);
  for (std::size_t slot = 0; slot < mine.size(); ++slot) {
    const unsigned int cell = mine[slot];
    const types::global_dof_index* indices = c.dofs(cell);
    int* out = &scatter_[slot * n * n];
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int j = 0; j < n; ++j)
        out[i * n + j] = constrained_[indices[i]] || constrained_[indices[j]]
                             ? -1
                             : tangent_.position(static_cast<int>(indices[i]), static_cast<int>(indices[j]));
  }
}

// g(x) at the supports' dofs is interpolated once per set_up (deal.II's interpolation visits every
// boundary face: 5.5 ms a frame on the anatomy at 3.6 mm) and scaled by the factor at each call,
// the same product ScaledField forms.
void LinearSystem::apply_supports(const std::vector<Support>& supports, double factor, Vector<double>& u) const {
  if (support_values_.size() != supports.size()) {
    support_values_.assign(supports.size(), {});
    for (std::size_t k = 0; k < supports.size(); ++k) {
      std::map<types::global_dof_index, double> values;
      const Support& support = supports[k];
      VectorTools::interpolate_boundary_values(*d_.mapping, d_.dof, support.boundary, ScaledField(support.field, 1.0),
                                               values, mask(support.components));
      support_values_[k].assign(values.begin(), values.end());
    }
  }
  for (const auto& values : support_values_)
    for (const auto& [index, value] : values) u[index] = factor * value;
}

void LinearSystem::set_rank_one(double c, const Vector<double>* g) {
  rank_one_c_ = g ? c : 0;
  rank_one_g_ = g;
  y_current_ = false;
  tangent_.set_rank_one(rank_one_c_, g ? g->begin() : nullptr);
}

void LinearSystem::account(const TangentSystem::SolveStats& stats) {
  times.factorisation_s += stats.factor_s;
  times.solve_s += stats.solve_s;
  times.linear_iterations += stats.iterations;
}

void LinearSystem::solve(const Vector<double>& rhs, Vector<double>& x, double tolerance, bool zero_guess) {
  x.reinit(rhs.size(), /*omit_zeroing_entries=*/!zero_guess);
  const TangentSystem::SolveStats stats = tangent_.solve(rhs.begin(), x.begin(), tolerance, zero_guess);
  account(stats);
  if (rank_one_c_ != 0 && !stats.rank_one) {
    // The solve was with K_s alone (multigrid): Sherman-Morrison, (K_s + c g g')^-1 b =
    // x - c (g.x) / (1 + c g.y) y, x = K_s^-1 b, y = K_s^-1 g.
    const Vector<double>& g = *rank_one_g_;
    if (!y_current_) {
      y_.reinit(g.size(), /*omit_zeroing_entries=*/y_.size() == g.size());
      account(tangent_.solve(g.begin(), y_.begin(), std::min(tolerance, 1e-10), /*zero_guess=*/false));
      y_current_ = true;
    }
    x.add(-rank_one_c_ * (g * x) / (1 + rank_one_c_ * (g * y_)), y_);
  }
  constraints_.distribute(x);
}

void LinearSystem::multiply(const double* const* x, double* const* y, int count) const {
  tangent_.multiply_columns(x, y, count);
  if (rank_one_c_ == 0) return;
  const double* g = rank_one_g_->begin();
  const std::size_t n = rank_one_g_->size();
  for (int k = 0; k < count; ++k) {
    double gx = 0;
    for (std::size_t i = 0; i < n; ++i) gx += g[i] * x[k][i];
    const double scale = rank_one_c_ * gx;
    for (std::size_t i = 0; i < n; ++i) y[k][i] += scale * g[i];
  }
}

void LinearSystem::apply_factorisation_to_rank_one_g(Vector<double>& w) {
  w.reinit(d_.n_dofs(), /*omit_zeroing_entries=*/true);
  TangentSystem::SolveStats stats = tangent_.apply_factorisation_to_rank_one_g(w.begin());
  stats.iterations = 1;
  account(stats);
}

void LinearSystem::apply_factorisation(const double* b, double* x, int columns) {
  TangentSystem::SolveStats stats = tangent_.apply_factorisation(b, x, columns);
  stats.iterations = 1;  // one blocked application
  account(stats);
}

}  // namespace fetouch::fem
