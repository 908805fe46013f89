#include "fem/inertia_term.h"

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

Dynamics Dynamics::hht(double alpha_h) {
  Dynamics d;
  d.newmark = true;
  d.hht_alpha = alpha_h;
  d.beta = (1 - alpha_h) * (1 - alpha_h) / 4;
  d.gamma = (1 - 2 * alpha_h) / 2;
  return d;
}

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
  if (dynamics.newmark && dynamics.hht_alpha != 0) {
    mass_scale_ = 1 / (1 + dynamics.hht_alpha);
    carried_.reinit(d_.n_dofs());
  }
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
  if (carried_.size() == 0) return;
  // Q+ = (alpha_h Q - M a+) / (1 + alpha_h), each rank's part from its own cells.
  Vector<double> mass_acceleration(u.size());
  mass_times(a_old_, mass_acceleration.begin(), 0, nullptr);
  const double alpha_h = dynamics_.hht_alpha;
  for (types::global_dof_index i = 0; i < u.size(); ++i)
    carried_[i] = (alpha_h * carried_[i] - mass_acceleration[i]) * mass_scale_;
}

void InertiaTerm::mass_times(const Vector<double>& x, double* out, double gain, AssemblyTarget* target) const {
  const Discretisation::Cells& c = d_.cells();
  const unsigned int n = c.n, nq = c.nq;
  const bool tangent = target && target->tangent;
  std::vector<double> local(n), cell_out(n), cell_matrix(std::size_t(n) * n);
  if (tangent) target->system->build_cell_scatter();
  for (const unsigned int k : d_.my_cells) {
    const types::global_dof_index* indices = c.dofs(k);
    const double* cell_jxw = c.jxw_of(k);
    d_.gather(k, x, local.data());
    std::fill(cell_out.begin(), cell_out.end(), 0.0);
    if (tangent) std::fill(cell_matrix.begin(), cell_matrix.end(), 0.0);
    for (unsigned int q = 0; q < nq; ++q) {
      const double* shape = &c.shape_values[q * c.nbase];
      const double w = density_[k] * cell_jxw[q];
      double field[3] = {0, 0, 0};
      for (unsigned int j = 0; j < n; ++j) field[c.component[j]] += shape[c.base[j]] * local[j];
      for (unsigned int i = 0; i < n; ++i) {
        cell_out[i] += w * shape[c.base[i]] * field[c.component[i]];
        if (!tangent) continue;
        for (unsigned int j = 0; j < n; ++j)
          if (c.component[j] == c.component[i]) cell_matrix[i * n + j] += gain * w * shape[c.base[i]] * shape[c.base[j]];
      }
    }
    for (unsigned int i = 0; i < n; ++i) out[indices[i]] += cell_out[i];
    if (!tangent) continue;
    const int* where = target->system->cell_scatter(k);
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int j = 0; j < n; ++j)
        if (where[i * n + j] >= 0) target->tangent[where[i * n + j]] += cell_matrix[i * n + j];
  }
}

// M (a+ / (1 + alpha_h) + alpha v+) - alpha_h / (1 + alpha_h) Q with the consistent mass into f_int,
// (c0 / (1 + alpha_h) + alpha dv+/du+) M into the tangent.
bool InertiaTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const std::vector<bool>& constrained = target.system->constrained();
  const Vector<double>& u = state.u;
  inertial_.reinit(u.size(), /*omit_zeroing_entries=*/true);
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    const double a_new = acceleration(u[i], i);
    inertial_[i] = mass_scale_ * a_new + dynamics_.rayleigh_mass_per_s * velocity(u[i], a_new, i);
  }
  const double gain = mass_scale_ * c0_ + dynamics_.rayleigh_mass_per_s * velocity_gain();
  Vector<double> internal(u.size());
  mass_times(inertial_, internal.begin(), gain, &target);
  if (carried_.size() != 0) internal.add(-dynamics_.hht_alpha * mass_scale_, carried_);
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    if (target.internal) target.internal[i] += internal[i];
    if (!constrained[i]) target.residual[i] -= internal[i];
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
