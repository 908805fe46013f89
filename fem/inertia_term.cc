#include "fem/inertia_term.h"

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

InertiaTerm::InertiaTerm(const Discretisation& discretisation, const Dynamics& dynamics)
    : d_(discretisation), dynamics_(dynamics) {
  const double dt = dynamics.time_step_s;
  if (dynamics.newmark)
    c0_ = 1 / (dynamics.beta * dt * dt), c1_ = 1 / (dynamics.beta * dt), c2_ = (1 - 2 * dynamics.beta) / (2 * dynamics.beta);
  else
    c0_ = 1 / (dt * dt), c1_ = 1 / dt, c2_ = 0;
  u_old_.reinit(d_.n_dofs());
  v_old_.reinit(d_.n_dofs());
  a_old_.reinit(d_.n_dofs());
  const Discretisation::Cells& c = d_.cells();
  density_.assign(d_.n_cells(), dynamics.density_kg_per_m3);
  for (unsigned int k = 0; k < d_.n_cells(); ++k)
    if (const auto region = dynamics.region_density_kg_per_m3.find(c.material_id[k]);
        region != dynamics.region_density_kg_per_m3.end())
      density_[k] = region->second;
}

double InertiaTerm::acceleration(double u_new, std::size_t i) const {
  return c0_ * (u_new - u_old_[i]) - c1_ * v_old_[i] - c2_ * a_old_[i];
}

double InertiaTerm::velocity(double u_new, double a_new, std::size_t i) const {
  const double dt = dynamics_.time_step_s;
  if (dynamics_.newmark) return v_old_[i] + dt * ((1 - dynamics_.gamma) * a_old_[i] + dynamics_.gamma * a_new);
  return (u_new - u_old_[i]) / dt;
}

double InertiaTerm::velocity_gain() const {
  return dynamics_.newmark ? dynamics_.gamma * dynamics_.time_step_s * c0_ : 1 / dynamics_.time_step_s;
}

void InertiaTerm::begin_solve(const Vector<double>& u) { u_old_ = u; }

void InertiaTerm::accept(const Vector<double>& u) {  // advance the time-stepping state
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    const double a_new = acceleration(u[i], i);
    const double v_new = velocity(u[i], a_new, i);
    a_old_[i] = a_new;
    v_old_[i] = v_new;
  }
}

// M (a+ + alpha v+) with the consistent mass into f_int, (c0 + alpha dv+/du+) M into the tangent.
bool InertiaTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const Discretisation::Cells& c = d_.cells();
  const std::vector<bool>& constrained = target.system->constrained();
  const Vector<double>& u = state.u;
  inertial_.reinit(u.size(), /*omit_zeroing_entries=*/true);
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    const double a_new = acceleration(u[i], i);
    inertial_[i] = a_new + dynamics_.rayleigh_mass_per_s * velocity(u[i], a_new, i);
  }
  const double gain = c0_ + dynamics_.rayleigh_mass_per_s * velocity_gain();
  const unsigned int n = c.n, nq = c.nq;
  std::vector<double> local(n), cell_internal(n), cell_matrix(std::size_t(n) * n);
  for (const unsigned int k : d_.my_cells) {
    const types::global_dof_index* indices = &c.indices[std::size_t(k) * n];
    d_.gather(k, inertial_, local.data());
    std::fill(cell_internal.begin(), cell_internal.end(), 0.0);
    std::fill(cell_matrix.begin(), cell_matrix.end(), 0.0);
    for (unsigned int q = 0; q < nq; ++q) {
      const double* shape = &c.shape_values[q * c.nbase];
      const double w = density_[k] * c.jxw[std::size_t(k) * nq + q];
      double field[3] = {0, 0, 0};
      for (unsigned int j = 0; j < n; ++j) field[c.component[j]] += shape[c.base[j]] * local[j];
      for (unsigned int i = 0; i < n; ++i) {
        cell_internal[i] += w * shape[c.base[i]] * field[c.component[i]];
        if (!target.tangent) continue;
        for (unsigned int j = 0; j < n; ++j)
          if (c.component[j] == c.component[i]) cell_matrix[i * n + j] += gain * w * shape[c.base[i]] * shape[c.base[j]];
      }
    }
    const int* where = target.tangent ? target.system->cell_scatter(k) : nullptr;
    for (unsigned int i = 0; i < n; ++i) {
      if (target.internal) target.internal[indices[i]] += cell_internal[i];
      if (!constrained[indices[i]]) target.residual[indices[i]] -= cell_internal[i];
      if (!target.tangent) continue;
      for (unsigned int j = 0; j < n; ++j)
        if (where[i * n + j] >= 0) target.tangent[where[i * n + j]] += cell_matrix[i * n + j];
    }
  }
  return true;
}

StiffnessDampingTerm::StiffnessDampingTerm(const InertiaTerm& inertia, std::vector<double> reference_tangent)
    : inertia_(inertia), k0_(std::move(reference_tangent)) {}

// beta K0 v+ into the residual, beta K0 dv+/du+ into the tangent.
bool StiffnessDampingTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const Vector<double>& u = state.u;
  const std::vector<bool>& constrained = target.system->constrained();
  Vector<double> velocities(u.size()), damping(u.size());
  for (types::global_dof_index i = 0; i < u.size(); ++i) velocities[i] = inertia_.velocity(u[i], inertia_.acceleration(u[i], i), i);
  target.system->tangent().multiply(k0_.data(), velocities.begin(), damping.begin());
  const double beta = inertia_.dynamics().rayleigh_stiffness_s, gain = beta * inertia_.velocity_gain();
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    if (target.internal) target.internal[i] += beta * damping[i];
    if (!constrained[i]) target.residual[i] -= beta * damping[i];
  }
  if (target.tangent)
    for (std::size_t k = 0; k < k0_.size(); ++k) target.tangent[k] += gain * k0_[k];
  return true;
}

}  // namespace fetouch::fem
