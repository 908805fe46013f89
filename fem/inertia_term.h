// Inertia and Rayleigh damping C = alpha M + beta K0, for a solve that is one time step of length
// dt: R(u) + M (a + alpha v) + beta K0 v = 0 at the new time, K0 the tangent of the reference state
// (so the damping is linear: a mode of frequency w is damped at the ratio
// zeta = alpha / (2 w) + beta w / 2), with
//   Newmark (beta, gamma):  a+ = (u+ - u - dt v)/(beta dt^2) - (1 - 2 beta)/(2 beta) a,
//                           v+ = v + dt ((1 - gamma) a + gamma a+)      (1/4, 1/2: no dissipation)
//   backward Euler:         v+ = (u+ - u)/dt,  a+ = (v+ - v)/dt          (first order, dissipative)
//   HHT-alpha (Hilber, Hughes & Taylor 1977), alpha_h in [-1/3, 0]: Newmark's updates with
//     beta = (1 - alpha_h)^2 / 4, gamma = (1 - 2 alpha_h) / 2, and the balance taken at t_n+1+alpha_h:
//       M a+ + (1 + alpha_h) (C v+ + S(u+)) - alpha_h (C v + S(u)) = 0,   S = f_int - f_ext,
//     second order, dissipating high frequencies (alpha_h = 0 is Newmark's average acceleration).
//     Divided by (1 + alpha_h) the other terms stay as they are: this one adds M a+ / (1 + alpha_h)
//     and the constant -alpha_h / (1 + alpha_h) Q, with Q = C v + S(u) of the step's start. At a
//     converged step the balance gives Q+ = (alpha_h Q - M a+) / (1 + alpha_h), so Q is carried
//     from the term's own quantities (Q = 0 at rest) and no other term needs to know the scheme.
// M is the consistent mass matrix of density rho. The state starts at rest.
//
// InertiaTerm carries the time-stepping state (u, v, a, and Q for HHT, at the step's start) and adds
// M (a+ / (1 + alpha_h) + alpha v+) (alpha_h = 0 but for HHT); StiffnessDampingTerm, built only when
// beta > 0, adds beta K0 v+ and reads that state.
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
  double hht_alpha = 0;  // in [-1/3, 0]; with newmark, beta and gamma from it (hht())
  double rayleigh_mass_per_s = 0;   // alpha
  double rayleigh_stiffness_s = 0;  // beta
  // HHT-alpha's Newmark parameters for alpha_h in [-1/3, 0].
  static Dynamics hht(double alpha_h);
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
  // M x (the consistent mass, this rank's cells) into `out`; with `tangent`, `gain` M into it too.
  void mass_times(const dealii::Vector<double>& x, double* out, double gain, AssemblyTarget* tangent) const;

  double c0_ = 0, c1_ = 0, c2_ = 0;  // a+ = c0 (u+ - u_old) - c1 v_old - c2 a_old
  double mass_scale_ = 1;            // 1 / (1 + alpha_h)
  dealii::Vector<double> u_old_, v_old_, a_old_;
  dealii::Vector<double> carried_;   // HHT: Q of the step's start (this rank's part), else empty
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
