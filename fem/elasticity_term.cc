#include "fem/elasticity_term.h"

#include <deal.II/lac/full_matrix.h>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <thread>

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

void require_decoupled(const Material& material) {
  double u1 = 0, u2 = 0;
  if (!material.volumetric(1.0, u1, u2))
    throw std::invalid_argument("the mean-dilatation formulation needs a decoupled material (neo_hookean_incompressible "
                                "or mooney_rivlin), not " + material.name());
}

ElasticityTerm::ElasticityTerm(const Discretisation& discretisation, const Material& body)
    : d_(discretisation), body_(body) {}

void ElasticityTerm::set_region_material(unsigned int material_id, const Material& material) {
  if (mean_dilatation_) require_decoupled(material);
  regions_[material_id] = &material;
  cell_material_.clear();
}

void ElasticityTerm::use_mean_dilatation(bool on) {
  if (on) {
    require_decoupled(body_);
    for (const auto& [id, material] : regions_) require_decoupled(*material);
  }
  mean_dilatation_ = on;
}

const Material& ElasticityTerm::material_of(unsigned int cell) const {
  if (cell_material_.empty()) {
    const Discretisation::Cells& c = d_.cells();
    cell_material_.assign(d_.n_cells(), &body_);
    for (unsigned int k = 0; k < d_.n_cells(); ++k) {
      const auto region = regions_.find(c.material_id[k]);
      if (region != regions_.end()) cell_material_[k] = region->second;
    }
  }
  return *cell_material_[cell];
}

// The cells add -f_int into r (free dofs), f_int into `internal` (if given) and, if
// `values`, the tangent into that value array. False if J <= 0 somewhere.
bool ElasticityTerm::assemble_cells(const std::vector<unsigned int>& cells, const Vector<double>& u, double* r,
                                    double* internal, double* values, const LinearSystem& system) const {
  const Discretisation::Cells& c = d_.cells();
  const std::vector<bool>& constrained = system.constrained();
  const bool tangent = values != nullptr;
  const unsigned int n = c.n, nq = c.nq;
  FullMatrix<double> cell_matrix(n, n);
  Vector<double> cell_internal(n);
  std::vector<double> u_local(n);
  std::vector<std::array<Tensor<1, 3>, 3>> a_grad(n);
  std::vector<double> volume_gradient(mean_dilatation_ ? n : 0);
  std::vector<Tensor2> F_at(nq);
  Tensor2 P;
  Tensor4 A;
  for (const unsigned int k : cells) {
    const types::global_dof_index* indices = &c.indices[std::size_t(k) * n];
    const Material& material = material_of(k);
    d_.gather(k, u, u_local.data());
    for (unsigned int q = 0; q < nq; ++q) F_at[q] = d_.deformation_gradient(k, q, u_local.data());
    cell_matrix = 0;
    cell_internal = 0;
    // Mean dilatation: U(J) becomes U(theta) of the cell's volume ratio theta = v / V, its pressure
    // p = U'(theta) constant over the cell.
    double reference_volume = 0, pressure = 0, pressure_stiffness = 0;
    if (mean_dilatation_) {
      double volume = 0;
      for (unsigned int q = 0; q < nq; ++q) {
        const double jxw = c.jxw[std::size_t(k) * nq + q];
        const double j = determinant(F_at[q]);
        if (!(j > 0)) return false;
        volume += j * jxw;
        reference_volume += jxw;
      }
      material.volumetric(volume / reference_volume, pressure, pressure_stiffness);
      std::fill(volume_gradient.begin(), volume_gradient.end(), 0.0);
    }
    for (unsigned int q = 0; q < nq; ++q) {
      const Tensor<1, 3>* grad = &c.gradients[(std::size_t(k) * nq + q) * c.nbase];
      const double jxw = c.jxw[std::size_t(k) * nq + q];
      const Tensor2& F = F_at[q];
      if (!material.evaluate(F, P, tangent ? &A : nullptr)) return false;
      if (mean_dilatation_) {
        // Swap the point's volumetric stress U'(J) J F^-T for the cell's p J F^-T, and in the
        // tangent U''(J) J^2 F^-T x F^-T + U'(J) d2J for p d2J, d2J = J (F^-T x F^-T - F^-T o F^-1).
        const double j = determinant(F);
        const Tensor2 f_inv_t = transpose(invert(F));
        double u1 = 0, u2 = 0;
        material.volumetric(j, u1, u2);
        const double excess = u1 - pressure;
        P -= excess * j * f_inv_t;
        if (tangent)
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              for (int cc = 0; cc < 3; ++cc)
                for (int dd = 0; dd < 3; ++dd)
                  A[a][b][cc][dd] -= u2 * j * j * f_inv_t[a][b] * f_inv_t[cc][dd] +
                                     excess * j * (f_inv_t[a][b] * f_inv_t[cc][dd] - f_inv_t[a][dd] * f_inv_t[cc][b]);
        for (unsigned int i = 0; i < n; ++i)  // dv/du_i = int J F^-T : grad N_i
          volume_gradient[i] += j * (f_inv_t[c.component[i]] * grad[c.base[i]]) * jxw;
      }
      if (tangent)  // a_grad[j][c] = A[c][.][c_j][.] grad phi_j, so that K_ij = grad phi_i . a_grad[j][c_i]
        for (unsigned int j = 0; j < n; ++j) {
          const Tensor<1, 3>& g = grad[c.base[j]];
          for (int ci = 0; ci < 3; ++ci)
            for (int J = 0; J < 3; ++J) {
              double v = 0;
              for (int L = 0; L < 3; ++L) v += A[ci][J][c.component[j]][L] * g[L];
              a_grad[j][ci][J] = v * jxw;
            }
        }
      for (unsigned int i = 0; i < n; ++i) {
        const unsigned int ci = c.component[i];
        const Tensor<1, 3>& g = grad[c.base[i]];
        cell_internal(i) += (P[ci][0] * g[0] + P[ci][1] * g[1] + P[ci][2] * g[2]) * jxw;
        if (!tangent) continue;
        for (unsigned int j = 0; j < n; ++j) cell_matrix(i, j) += g * a_grad[j][ci];
      }
    }
    if (mean_dilatation_ && tangent) {  // U''(theta)/V (dv/du)(dv/du)'
      const double scale = pressure_stiffness / reference_volume;
      for (unsigned int i = 0; i < n; ++i)
        for (unsigned int j = 0; j < n; ++j) cell_matrix(i, j) += scale * volume_gradient[i] * volume_gradient[j];
    }
    // Homogeneous constraints: constrained rows and columns are dropped (finish() puts their diagonal).
    const int* where = tangent ? system.cell_scatter(k) : nullptr;
    for (unsigned int i = 0; i < n; ++i) {
      if (internal) internal[indices[i]] += cell_internal(i);
      if (!constrained[indices[i]]) r[indices[i]] -= cell_internal(i);
      if (!tangent) continue;
      for (unsigned int j = 0; j < n; ++j)
        if (where[i * n + j] >= 0) values[where[i * n + j]] += cell_matrix(i, j);
    }
  }
  return true;
}

void ElasticityTerm::plan_threads() const {
  plan_ = {};
  planned_ = true;
  const std::vector<unsigned int>& mine = d_.my_cells;
  if (threads_ < 2 || d_.ranks > 1 || mine.size() < 2 * kCellsPerThread) {
    plan_[0] = mine;
    return;
  }
  // Cut at the median of the cell centres along the mesh's longest extent.
  std::vector<Point<3>> centre(d_.n_cells());
  {
    unsigned int k = 0;
    for (const auto& cell : d_.tria.active_cell_iterators()) centre[k++] = cell->center();
  }
  Point<3> low = centre[mine[0]], high = low;
  for (const unsigned int k : mine)
    for (int a = 0; a < 3; ++a) low[a] = std::min(low[a], centre[k][a]), high[a] = std::max(high[a], centre[k][a]);
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (high[a] - low[a] > high[axis] - low[axis]) axis = a;
  std::vector<unsigned int> order = mine;
  const auto below = [&](unsigned int x, unsigned int y) {
    return centre[x][axis] < centre[y][axis] || (centre[x][axis] == centre[y][axis] && x < y);
  };
  std::nth_element(order.begin(), order.begin() + order.size() / 2, order.end(), below);
  std::vector<unsigned char> side(d_.n_cells(), 0), touched(d_.n_dofs(), 0);
  for (std::size_t i = 0; i < order.size(); ++i) side[order[i]] = i < order.size() / 2 ? 1 : 2;
  const Discretisation::Cells& c = d_.cells();
  for (const unsigned int k : mine)
    for (unsigned int i = 0; i < c.n; ++i) touched[c.indices[std::size_t(k) * c.n + i]] |= side[k];
  for (const unsigned int k : mine) {  // in cell order, as one thread would take them
    bool shared = false;
    for (unsigned int i = 0; i < c.n && !shared; ++i) shared = touched[c.indices[std::size_t(k) * c.n + i]] == 3;
    plan_[shared ? 2 : side[k] - 1].push_back(k);
  }
}

bool ElasticityTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const LinearSystem& system = *target.system;
  material_of(0);                                // per-cell materials, the scatter map and the
  if (target.tangent) system.cell_scatter(0);    // threads' cells are built before the threads run
  if (!planned_) plan_threads();
  const auto run = [&](const std::vector<unsigned int>& cells) {
    return assemble_cells(cells, state.u, target.residual, target.internal, target.tangent, system);
  };
  if (plan_[1].empty()) return run(plan_[0]);
  bool second_ok = true;
  std::thread worker([&] { second_ok = run(plan_[1]); });
  const bool first_ok = run(plan_[0]);
  worker.join();
  return first_ok && second_ok && run(plan_[2]);
}

}  // namespace fetouch::fem
