// The time integrators against their closed forms, on a single-degree-of-freedom oscillator: one Q1
// cell on rollers (a uniaxial-strain column of height L, base fixed), hit by a step traction t on
// its top. The top moves as one: stiffness k = M A / L (M = lambda + 2 mu), consistent mass
// m = rho A L / 3 (u_z = U z / L), so omega^2 = 3 M / (rho L^2), and it rings about U_s = t L / M.
//
// A scheme's free response is x+ = A(Omega) x with Omega = omega dt; its principal roots
// lambda = exp(Omega_bar (-xi_bar +- i)) give the numerical damping xi_bar and the period
// T_bar / T = Omega / Omega_bar (Hughes, The Finite Element Method, section 9.3):
//   Newmark average acceleration: |lambda| = 1, Omega_bar = 2 atan(Omega / 2)
//   backward Euler (v+ = (u+ - u)/dt, a+ = (v+ - v)/dt): lambda = (1 +- i Omega) / (1 + Omega^2)
//   HHT-alpha: the roots of A's characteristic polynomial, A written from the scheme's definition
//     (Hilber, Hughes & Taylor 1977).
// The solver's top displacement is fitted with d+2 = p d+1 + q d (the principal pair, once the
// spurious root has died out), which gives lambda = p/2 +- i sqrt(-q - p^2/4).
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <Eigen/Dense>

#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

constexpr double kLength = 0.05, kYoung = 5000, kPoisson = 0.3, kDensity = 1000, kTraction = -20;

double omega() {
  const double modulus = lame_lambda(kYoung, kPoisson) + 2 * lame_mu(kYoung, kPoisson);
  return std::sqrt(3 * modulus / (kDensity * kLength * kLength));
}

// The top's deviation from its static displacement after each of `steps` steps.
std::vector<double> ring(const QuasiStaticSolver::Dynamics& scheme, double big_omega, int steps) {
  const double lambda = lame_lambda(kYoung, kPoisson), mu = lame_mu(kYoung, kPoisson);
  const double u_static = kTraction * kLength / (lambda + 2 * mu);
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_rectangle(tria, {1, 1, 1}, Point<3>(), Point<3>(0.01, 0.01, kLength), true);
  const LinearElastic material(lambda, mu);
  QuasiStaticSolver solver(tria, material, 1);
  for (const unsigned int side : {0u, 1u}) solver.prescribe_displacement(side, {true, false, false}, Tensor<1, 3>());
  for (const unsigned int side : {2u, 3u}) solver.prescribe_displacement(side, {false, true, false}, Tensor<1, 3>());
  solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  Tensor<1, 3> t;
  t[2] = kTraction;
  solver.apply_traction(5, t);
  QuasiStaticSolver::Dynamics dynamics = scheme;
  dynamics.density_kg_per_m3 = kDensity;
  dynamics.time_step_s = big_omega / omega();
  solver.enable_dynamics(dynamics);
  NewtonSettings settings;
  settings.absolute_tolerance = 1e-16;
  settings.relative_tolerance = 1e-13;
  std::vector<double> deviation;
  for (int step = 0; step < steps; ++step) {
    const SolveReport report = solver.solve(settings);
    EXPECT_TRUE(report.converged) << report.failure;
    deviation.push_back(solver.displacement_at(Point<3>(0.005, 0.005, kLength))[2] - u_static);
  }
  return deviation;
}

// The principal root fitted to the response from step `first` on (least squares on d+2 = p d+1 + q d).
std::complex<double> fitted_root(const std::vector<double>& d, std::size_t first) {
  Eigen::MatrixXd a(static_cast<Eigen::Index>(d.size() - first - 2), 2);
  Eigen::VectorXd b(a.rows());
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const std::size_t n = first + static_cast<std::size_t>(r);
    a(r, 0) = d[n + 1], a(r, 1) = d[n], b(r) = d[n + 2];
  }
  const Eigen::Vector2d pq = a.colPivHouseholderQr().solve(b);
  const double p = pq(0), q = pq(1);
  return {p / 2, std::sqrt(std::max(0.0, -q - p * p / 4))};
}

// HHT's amplification matrix for (d, dt v, dt^2 a) of the free, undamped oscillator, from the
// scheme's three equations; its complex root of positive imaginary part.
std::complex<double> hht_root(double alpha, double big_omega) {
  const double beta = (1 - alpha) * (1 - alpha) / 4, gamma = (1 - 2 * alpha) / 2, w2 = big_omega * big_omega;
  Eigen::Matrix3d amplification;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d x = Eigen::Vector3d::Unit(j);  // d, dt v, dt^2 a (m = 1, k = Omega^2 / dt^2)
    // a+ (1 + (1 + alpha) beta W2) = -W2 d - (1 + alpha) W2 (dt v + (1/2 - beta) dt^2 a)  (times dt^2)
    const double a_new = (-w2 * x(0) - (1 + alpha) * w2 * (x(1) + (0.5 - beta) * x(2))) / (1 + (1 + alpha) * beta * w2);
    amplification(0, j) = x(0) + x(1) + (0.5 - beta) * x(2) + beta * a_new;
    amplification(1, j) = x(1) + (1 - gamma) * x(2) + gamma * a_new;
    amplification(2, j) = a_new;
  }
  const Eigen::Vector3cd roots = amplification.eigenvalues();
  std::complex<double> principal;
  for (int k = 0; k < 3; ++k)
    if (roots(k).imag() > principal.imag()) principal = roots(k);
  return principal;
}

struct Figures {
  double damping_ratio, period_ratio;  // xi_bar, T_bar / T
};
Figures figures(std::complex<double> root, double big_omega) {
  const double omega_bar = std::arg(root);
  return {-std::log(std::abs(root)) / omega_bar, big_omega / omega_bar};
}

void expect_root(const std::complex<double>& measured, const std::complex<double>& closed_form, double big_omega,
                 const char* scheme) {
  const Figures m = figures(measured, big_omega), c = figures(closed_form, big_omega);
  std::printf("%s at Omega = %.2f: damping ratio %.6f (closed form %.6f), period ratio %.6f (closed form %.6f)\n", scheme,
              big_omega, m.damping_ratio, c.damping_ratio, m.period_ratio, c.period_ratio);
  // The fit reads a linear recurrence run to a residual of 1e-13: its roots agree far below the
  // figures' own size (damping ratios of 1e-2, period errors of 1e-2); 1e-6 leaves round-off room.
  EXPECT_NEAR(std::abs(measured), std::abs(closed_form), 1e-6) << scheme;
  EXPECT_NEAR(std::arg(measured), std::arg(closed_form), 1e-6) << scheme;
}

TEST(TimeIntegrators, NewmarkKeepsTheAmplitudeAndLengthensThePeriodAsTheTrapezoidalRule) {
  for (const double big_omega : {0.3, 0.8}) {
    const std::vector<double> d = ring(QuasiStaticSolver::Dynamics(), big_omega, 120);
    expect_root(fitted_root(d, 2), std::polar(1.0, 2 * std::atan(big_omega / 2)), big_omega, "Newmark");
  }
}

TEST(TimeIntegrators, BackwardEulerDampsAsItsClosedForm) {
  QuasiStaticSolver::Dynamics scheme;
  scheme.newmark = false;
  for (const double big_omega : {0.3, 0.8}) {
    const std::vector<double> d = ring(scheme, big_omega, 60);
    expect_root(fitted_root(d, 2), std::complex<double>(1, big_omega) / (1 + big_omega * big_omega), big_omega,
                "backward Euler");
  }
}

TEST(TimeIntegrators, HhtDampsAsItsAmplificationMatrixSays) {
  for (const double alpha : {-0.05, -0.1, -1.0 / 3.0})
    for (const double big_omega : {0.3, 0.8}) {
      const std::vector<double> d = ring(QuasiStaticSolver::Dynamics::hht(alpha), big_omega, 120);
      char name[48];
      std::snprintf(name, sizeof name, "HHT alpha %.3f", alpha);
      expect_root(fitted_root(d, 10), hht_root(alpha, big_omega), big_omega, name);
    }
}

// What makes HHT useful: its numerical damping grows faster than the frequency (second-order
// accurate, so at least as Omega^2; the closed form's expansion starts at Omega^3), so the resolved
// low modes keep their amplitude and the unresolved high ones die; the period error is O(Omega^2).
TEST(TimeIntegrators, HhtDampsHighFrequenciesAndKeepsLowOnes) {
  const double alpha = -0.1;
  std::vector<Figures> f;
  for (const double big_omega : {0.05, 0.1})
    f.push_back(figures(fitted_root(ring(QuasiStaticSolver::Dynamics::hht(alpha), big_omega, 400), 10), big_omega));
  std::printf("HHT alpha -0.1: damping ratio %.3e at Omega 0.05, %.3e at 0.1 (x%.1f)\n", f[0].damping_ratio, f[1].damping_ratio,
              f[1].damping_ratio / f[0].damping_ratio);
  EXPECT_GT(f[0].damping_ratio, 0);
  EXPECT_GT(f[1].damping_ratio, 4 * f[0].damping_ratio);
  EXPECT_LT(std::abs(f[0].period_ratio - 1), 0.05 * 0.05);
  EXPECT_LT(std::abs(f[1].period_ratio - 1), 0.1 * 0.1);
}

}  // namespace
}  // namespace fetouch::fem
