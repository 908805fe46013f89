// Inertia against the wave equation: a bar on rollers (a 1D P-wave column) fixed at its base and hit
// by a step traction at its top. In the continuum the top oscillates about its static displacement
// with period T = 4 L / c, c = sqrt((lambda + 2 mu) / rho). Newmark's average acceleration keeps the
// amplitude; backward Euler damps it.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

struct Oscillation {
  double half_period_s = 0;          // mean spacing of the crossings of the static value
  double first_amplitude = 0, last_amplitude = 0;  // over the first and the last period
  double expected_half_period_s = 0;
  // The fundamental's amplitude in the first and the third period (projection on its sine and
  // cosine, to which the odd harmonics of the step response are orthogonal over a period).
  double first_fundamental = 0, third_fundamental = 0;
  double omega = 0;                  // of the fundamental, rad/s
};

Oscillation hit_the_bar(bool newmark, double stiffness_damping_s = 0) {
  const double length = 0.05, e = 5000, nu = 0.3, rho = 1000, traction = -20;
  const double lambda = lame_lambda(e, nu), mu = lame_mu(e, nu), modulus = lambda + 2 * mu;
  const double c = std::sqrt(modulus / rho), period = 4 * length / c, u_static = traction * length / modulus;
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_rectangle(tria, {1, 1, 12}, Point<3>(), Point<3>(0.01, 0.01, length), true);
  const LinearElastic material(lambda, mu);
  QuasiStaticSolver solver(tria, material, 2);
  solver.prescribe_displacement(0, {true, false, false}, Tensor<1, 3>());
  solver.prescribe_displacement(1, {true, false, false}, Tensor<1, 3>());
  solver.prescribe_displacement(2, {false, true, false}, Tensor<1, 3>());
  solver.prescribe_displacement(3, {false, true, false}, Tensor<1, 3>());
  solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  Tensor<1, 3> t;
  t[2] = traction;
  solver.apply_traction(5, t);
  QuasiStaticSolver::Dynamics dynamics;
  dynamics.density_kg_per_m3 = rho;
  dynamics.time_step_s = period / 200;
  dynamics.newmark = newmark;
  dynamics.rayleigh_stiffness_s = stiffness_damping_s;
  solver.enable_dynamics(dynamics);
  NewtonSettings settings;
  settings.absolute_tolerance = 1e-14;
  std::vector<double> deviation;  // u_top - u_static per step
  for (int step = 0; step < 600; ++step) {  // three periods
    const SolveReport report = solver.solve(settings);
    EXPECT_TRUE(report.converged) << report.failure;
    deviation.push_back(solver.displacement_at(Point<3>(0.005, 0.005, length))[2] - u_static);
  }
  Oscillation o;
  o.expected_half_period_s = period / 2;
  std::vector<double> crossings;
  for (size_t k = 1; k < deviation.size(); ++k)
    if ((deviation[k - 1] < 0) != (deviation[k] < 0))
      crossings.push_back(dynamics.time_step_s * (k - 1 + deviation[k - 1] / (deviation[k - 1] - deviation[k]) + 1));
  if (crossings.size() >= 2) o.half_period_s = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  for (size_t k = 0; k < 200; ++k) o.first_amplitude = std::max(o.first_amplitude, std::abs(deviation[k]));
  for (size_t k = 400; k < 600; ++k) o.last_amplitude = std::max(o.last_amplitude, std::abs(deviation[k]));
  o.omega = 2 * M_PI / period;
  const auto fundamental = [&](size_t begin) {
    double sine = 0, cosine = 0;
    for (size_t k = begin; k < begin + 200; ++k) {
      const double time = dynamics.time_step_s * (k + 1);
      sine += deviation[k] * std::sin(o.omega * time) / 100, cosine += deviation[k] * std::cos(o.omega * time) / 100;
    }
    return std::hypot(sine, cosine);
  };
  o.first_fundamental = fundamental(0);
  o.third_fundamental = fundamental(400);
  std::printf("%s: half period %.5f s (wave equation %.5f s), amplitude %.3e -> %.3e m (static %.3e m)\n",
              newmark ? "Newmark" : "backward Euler", o.half_period_s, o.expected_half_period_s, o.first_amplitude,
              o.last_amplitude, std::abs(u_static));
  return o;
}

TEST(Dynamics, NewmarkRingsAtTheWavePeriodWithoutLosingAmplitude) {
  const Oscillation o = hit_the_bar(true);
  // Mesh dispersion (12 Q2 cells) and the time step (T/200) each shift the period by well under 1 %.
  EXPECT_NEAR(o.half_period_s, o.expected_half_period_s, 0.015 * o.expected_half_period_s);
  EXPECT_NEAR(o.last_amplitude, o.first_amplitude, 0.05 * o.first_amplitude);
}

// Stiffness-proportional Rayleigh damping C = beta K0 damps a mode of frequency w at the ratio
// zeta = beta w / 2: over two periods the fundamental decays by exp(-zeta w 2T) = exp(-4 pi zeta)
// (undamped, Newmark keeps it: the test above).
TEST(Dynamics, StiffnessDampingDecaysTheFundamentalAtItsRatio) {
  const double zeta = 0.03;
  const double c = std::sqrt((lame_lambda(5000, 0.3) + 2 * lame_mu(5000, 0.3)) / 1000), omega = 2 * M_PI / (4 * 0.05 / c);
  const Oscillation o = hit_the_bar(true, 2 * zeta / omega);
  const double expected = std::exp(-4 * M_PI * zeta), measured = o.third_fundamental / o.first_fundamental;
  std::printf("beta = %.3e s: fundamental %.3e -> %.3e m, ratio %.4f (exp(-4 pi zeta) = %.4f)\n", 2 * zeta / omega,
              o.first_fundamental, o.third_fundamental, measured, expected);
  EXPECT_NEAR(measured, expected, 0.03);
}

TEST(Dynamics, BackwardEulerDampsTheSameOscillation) {
  const Oscillation o = hit_the_bar(false);
  EXPECT_LT(o.last_amplitude, 0.8 * o.first_amplitude);
}

}  // namespace
}  // namespace fetouch::fem
