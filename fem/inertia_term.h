// Inertia and Rayleigh damping C = alpha M + beta K0, for a solve that is one time step of length
// dt: R(u) + M (a + alpha v) + beta K0 v = 0 at the new time, K0 the tangent of the reference state
// (so the damping is linear: a mode of frequency w is damped at the ratio
// zeta = alpha / (2 w) + beta w / 2), with
//   Newmark (beta, gamma):  a+ = (u+ - u - dt v)/(beta dt^2) - (1 - 2 beta)/(2 beta) a,
//                           v+ = v + dt ((1 - gamma) a + gamma a+)      (1/4, 1/2: no dissipation)
//   backward Euler:         v+ = (u+ - u)/dt,  a+ = (v+ - v)/dt          (first order, dissipative)
// M is the consistent mass matrix of density rho. The state starts at rest.
//
// InertiaTerm carries the time-stepping state (u, v, a at the step's start) and adds M (a+ + alpha v+);
// StiffnessDampingTerm, built only when beta > 0, adds beta K0 v+ and reads that state.
#pragma once

#include <map>
#include <vector>

#include "fem/discretisation.h"
#include "fem/term.h"

namespace fetouch::fem {

struct Dynamics {
  double density_kg_per_m3 = 1000;
  std::map<unsigned int, double> region_density_kg_per_m3;  // by material id; others density_kg_per_m3
  double time_step_s = 0.05;
  bool newmark = true;  // false: backward Euler
  double beta = 0.25, gamma = 0.5;
  double rayleigh_mass_per_s = 0;   // alpha
  double rayleigh_stiffness_s = 0;  // beta
};

class InertiaTerm final : public Term {
 public:
  InertiaTerm(const Discretisation& discretisation, const Dynamics& dynamics);
  const char* name() const override { return "inertia"; }
  bool distributed() const override { return true; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;
  void begin_solve(const dealii::Vector<double>& u) override;
  void accept(const dealii::Vector<double>& u) override;

  const Dynamics& dynamics() const { return dynamics_; }
  double acceleration(double u_new, std::size_t i) const;
  double velocity(double u_new, double a_new, std::size_t i) const;
  double velocity_gain() const;  // dv+/du+

 private:
  const Discretisation& d_;
  Dynamics dynamics_;
  double c0_ = 0, c1_ = 0, c2_ = 0;  // a+ = c0 (u+ - u_old) - c1 v_old - c2 a_old
  dealii::Vector<double> u_old_, v_old_, a_old_;
  dealii::Vector<double> inertial_;  // a+ + alpha v+ per dof, at the assembled state
  std::vector<double> density_;      // per cell
};

class StiffnessDampingTerm final : public Term {
 public:
  // `reference_tangent`: K0's values in the tangent's pattern, constrained diagonals zero.
  StiffnessDampingTerm(const InertiaTerm& inertia, std::vector<double> reference_tangent);
  const char* name() const override { return "damping"; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;

 private:
  const InertiaTerm& inertia_;
  std::vector<double> k0_;
};

}  // namespace fetouch::fem
