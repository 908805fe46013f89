// The lifted (monodromy) analysis against independent answers: closed-form poles, Jury's test,
// and brute-force lockstep simulation of the loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "haptics/normal_loop.h"
#include "haptics/stability_analysis.h"

namespace fetouch::haptics {
namespace {

using C = std::complex<double>;

double max_modulus(const std::vector<C>& roots) {
  double r = 0;
  for (const auto& z : roots) r = std::max(r, std::abs(z));
  return r;
}

TEST(ClosedForms, PZohPoleAndRange) {
  const double k0 = 1.0, b0 = 0.3;
  for (double kh : {-0.9, 0.2, 1.0, 1.5, 1.59}) {
    const auto r = analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, k0, b0, kh));
    EXPECT_NEAR(r.spectral_radius, std::abs((b0 - kh) / (k0 + b0)), 1e-12) << kh;
    EXPECT_EQ(r.stable(), -k0 < kh && kh < k0 + 2 * b0) << kh;
  }
  EXPECT_FALSE(analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, k0, b0, 1.61)).stable());
  EXPECT_FALSE(analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, k0, b0, -1.01)).stable());
}

TEST(ClosedForms, PFohPolesOnTheImaginaryAxisWithoutDamping) {
  const double k0 = 2.0, kh = 0.5;
  const auto r = analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::foh, 50, k0, 0, kh));
  // Poles at +-j sqrt(Kh/K0) = +-0.5j; the other eigenvalues are delays at 0.
  int found = 0;
  for (const auto& z : r.poles)
    if (std::abs(z - C(0, std::sqrt(kh / k0))) < 1e-9 || std::abs(z - C(0, -std::sqrt(kh / k0))) < 1e-9)
      ++found;
  EXPECT_EQ(found, 2);
  EXPECT_NEAR(r.spectral_radius, 0.5, 1e-9);
}

TEST(ClosedForms, PiZohDeadbeat) {
  // Kh = K0 and N I = K0 with B0 = 0: characteristic polynomial K0 z^2, both poles at 0.
  const auto r = analyse(LoopParameters::scalar(LocalModelKind::pi, HoldKind::zoh, 50, 1.0, 0, 1.0, 1.0 / 50));
  // Zero is a defective eigenvalue (a Jordan block of size k with the delay states), which numerical
  // eigenvalues resolve only to about eps^(1/k) ~ 1e-5; the exact statement is nilpotency:
  // Phi^n = 0 for the n x n monodromy, to round-off.
  EXPECT_LT(r.spectral_radius, 1e-4);
  Eigen::MatrixXd power = Eigen::MatrixXd::Identity(r.monodromy.rows(), r.monodromy.cols());
  for (int i = 0; i < r.monodromy.rows(); ++i) power = power * r.monodromy;
  EXPECT_LT(power.norm(), 1e-12);
}

TEST(ClosedForms, PiZohJuryInequalitiesOfTheArchitecturePage) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 2);
  const int n = 50;
  for (int t = 0; t < 3000; ++t) {
    const double k0 = u(rng) + 0.05, b0 = 0.5 * u(rng), kh = 1.5 * u(rng) - 0.5, ni = 1.5 * u(rng) - 0.3;
    const bool jury = ni > 0 && ni < k0 + kh && ni > kh - k0 - 2 * b0 && 2 * kh < 2 * k0 + 4 * b0 + ni;
    const auto r = analyse(LoopParameters::scalar(LocalModelKind::pi, HoldKind::zoh, n, k0, b0, kh, ni / n));
    if (std::abs(r.spectral_radius - 1) < 1e-9) continue;  // on the boundary either answer is fair
    EXPECT_EQ(r.stable(), jury) << "K0 " << k0 << " B0 " << b0 << " Kh " << kh << " NI " << ni;
  }
}

// 10,000 random parameter sets per local-model/hold pair: the monodromy's spectral radius equals the
// largest root modulus of the closed-form polynomial, Jury's verdict agrees, and a brute-force
// lockstep run of the same set agrees away from the boundary.
// Growth or decay of a long lockstep run from a disturbed state, with the device held still.
double simulated_growth(const LoopParameters& p, int frames) {
  // The largest force over frames 5..9 against the largest over the last five.
  const int m = static_cast<int>(p.stiffness.rows());
  NormalLoop loop = make_loop(p);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(m);
  // Disturb: the device presses for one frame, then holds still at 0.
  for (int k = 0; k < p.ratio; ++k) loop.tick(Eigen::VectorXd::Ones(m));
  double early = 0, late = 0;
  for (int j = 0; j < frames; ++j)
    for (int k = 0; k < p.ratio; ++k) {
      const double f = loop.tick(still).norm();
      if (j >= 5 && j < 10) early = std::max(early, f);
      if (j >= frames - 5) late = std::max(late, f);
    }
  return late / std::max(early, 1e-300);
}

std::string pair_name(std::pair<LocalModelKind, HoldKind> pair) {
  const char* models[] = {"P", "PI", "Smith", "PISmith"};
  return std::string(models[static_cast<int>(pair.first)]) + (pair.second == HoldKind::zoh ? "_ZOH" : "_FOH");
}

class AgainstClosedForm : public ::testing::TestWithParam<std::pair<LocalModelKind, HoldKind>> {};

TEST_P(AgainstClosedForm, SpectralRadiusMatchesPolynomialRoots) {
  const auto [kind, hold] = GetParam();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  int compared = 0, simulated = 0;
  for (int t = 0; t < 10000; ++t) {
    const int n = 1 + static_cast<int>(u(rng) * 100);
    const double k0 = 0.05 + 2 * u(rng), b0 = u(rng), kh = 2.5 * u(rng) - 0.5;
    const double integral = kind == LocalModelKind::pi ? (1.5 * u(rng) - 0.2) / n : 0;
    const auto p = LoopParameters::scalar(kind, hold, n, k0, b0, kh, integral);
    const auto coefficients = characteristic_polynomial(p);
    const auto roots = polynomial_roots(coefficients);
    const double closed = max_modulus(roots);
    // Near a repeated root both eigenvalues and roots lose accuracy (to ~sqrt(eps)); compare only
    // where the roots are distinct enough for 1e-9 to be meaningful.
    bool separated = true;
    for (size_t a = 0; a < roots.size(); ++a)
      for (size_t b = a + 1; b < roots.size(); ++b)
        separated = separated && std::abs(roots[a] - roots[b]) > 1e-3;
    if (!separated) continue;
    ++compared;
    const auto r = analyse(p);
    ASSERT_NEAR(r.spectral_radius, closed, 1e-9 * std::max(1.0, closed))
        << "N " << n << " K0 " << k0 << " B0 " << b0 << " Kh " << kh << " I " << integral;
    if (std::abs(closed - 1) > 1e-6) {
      ASSERT_EQ(r.stable(), jury_stable(coefficients));
    }
    // The same set, simulated: away from the boundary (|rho - 1| > 0.05) a run long enough for
    // rho^frames to pass e^(+-6) decays or grows as the verdict says.
    // A second mode close in modulus to the first can dominate a run for long (an unstable 1.05
    // behind a decaying -0.97 takes a hundred frames to show): the run also lasts until the largest
    // mode leads the second by e^8.
    double second = 0;
    for (const auto& z : roots)
      if (std::abs(z) < closed - 1e-12) second = std::max(second, std::abs(z));
    const double frames_needed = 15 + 6 / std::abs(std::log(closed)) + (second > 0 ? 8 / std::log(closed / second) : 0);
    if (std::abs(closed - 1) > 0.05 && frames_needed < 800) {
      const int frames = std::max(40, static_cast<int>(frames_needed));
      ASSERT_EQ(closed < 1, simulated_growth(p, frames) < 1)
          << "N " << n << " K0 " << k0 << " B0 " << b0 << " Kh " << kh << " I " << integral;
      ++simulated;
    }
  }
  EXPECT_GT(compared, 9500);
  EXPECT_GT(simulated, 7000);  // the rest lie within 0.05 of the boundary
}

INSTANTIATE_TEST_SUITE_P(Pairs, AgainstClosedForm,
                         ::testing::Values(std::make_pair(LocalModelKind::p, HoldKind::zoh),
                                           std::make_pair(LocalModelKind::p, HoldKind::foh),
                                           std::make_pair(LocalModelKind::pi, HoldKind::zoh),
                                           std::make_pair(LocalModelKind::pi, HoldKind::foh)),
                         [](const auto& param_info) { return pair_name(param_info.param); });

// Every verdict of the analysis on a grid of 2,250 points per local-model/hold pair (all eight),
// confirmed by a long lockstep run: the run lasts until rho^frames is beyond e^(+-6), so decay and
// growth cannot be confused with a transient. Points within 0.003 of rho = 1 would need tens of
// thousands of frames; they are counted and must stay a small minority.
class EveryPair : public ::testing::TestWithParam<std::pair<LocalModelKind, HoldKind>> {};

TEST_P(EveryPair, VerdictsOnAGridAreConfirmedBySimulation) {
  const auto [kind, hold] = GetParam();
  const bool integral = has_integrator(kind);
  int confirmed = 0, on_boundary = 0, stable = 0;
  for (int a = 0; a < 50; ++a)
    for (int b = 0; b < 45; ++b) {
      // P and PI: (Kh, K0) and (Kh, N I) at K0 = 1, B0 = 0.1. Smith variants, robust to far larger
      // gains: (Kh, K0) with the predictor's compliance fixed at W = 1 while K0 varies (model
      // mismatch, which is what destabilises them), N I = 0.3 for PI + Smith.
      const bool smith = has_predictor(kind);
      const double kh = smith ? -0.5 + 8.5 * a / 49 : -0.2 + 2.6 * a / 49;
      const double ni = smith ? (integral ? 0.3 : 0.0) : integral ? 0.01 + 2.0 * b / 44 : 0.0;
      const double k0 = smith ? 0.1 + 2.0 * b / 44 : integral ? 1.0 : 0.3 + 2.0 * b / 44;
      auto p = LoopParameters::scalar(kind, hold, 50, k0, 0.1, kh, ni / 50);
      p.compliance = Eigen::MatrixXd::Constant(1, 1, 1.0);
      const double rho = analyse(p).spectral_radius;
      if (std::abs(rho - 1) < 3e-3) {
        ++on_boundary;
        continue;
      }
      const int frames = std::clamp(static_cast<int>(6 / std::abs(std::log(rho))) + 15, 40, 2500);
      const double growth = simulated_growth(p, frames);
      ASSERT_EQ(rho < 1, growth < 1) << "Kh " << kh << " NI " << ni << " K0 " << k0 << " rho " << rho << " growth " << growth;
      ++confirmed;
      stable += rho < 1;
    }
  EXPECT_LT(on_boundary, 2250 / 50);
  EXPECT_GE(confirmed + on_boundary, 2250);
  // The grid spans both verdicts.
  EXPECT_GT(stable, 100);
  EXPECT_GT(confirmed - stable, 100);
}

INSTANTIATE_TEST_SUITE_P(
    Grid, EveryPair,
    ::testing::Values(std::make_pair(LocalModelKind::p, HoldKind::zoh), std::make_pair(LocalModelKind::p, HoldKind::foh),
                      std::make_pair(LocalModelKind::pi, HoldKind::zoh), std::make_pair(LocalModelKind::pi, HoldKind::foh),
                      std::make_pair(LocalModelKind::smith, HoldKind::zoh), std::make_pair(LocalModelKind::smith, HoldKind::foh),
                      std::make_pair(LocalModelKind::pi_smith, HoldKind::zoh),
                      std::make_pair(LocalModelKind::pi_smith, HoldKind::foh)),
    [](const auto& param_info) { return pair_name(param_info.param); });

// Steady states and the seed's numeric examples, with a step of the device into the surface.
struct StepResponse {
  double force, surface;
};
StepResponse final_values(const LoopParameters& p, int frames) {
  NormalLoop loop = make_loop(p);
  const Eigen::VectorXd step = Eigen::VectorXd::Ones(1);
  double force = 0;
  for (int k = 0; k < frames * p.ratio; ++k) force = loop.tick(step)(0);
  return {force, loop.surface()(0)};
}

TEST(SteadyState, ProportionalIsSofterThanTheTissue) {
  const auto r = final_values(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, 0.9, 0, 0.1), 200);
  EXPECT_NEAR(r.force, 0.9 * 0.1 / (0.9 + 0.1), 1e-12);
  EXPECT_NEAR(r.surface, 0.1, 1e-12);  // one tenth of the device step
}

TEST(SteadyState, IntegralRendersTheTissueStiffness) {
  const auto r = final_values(LoopParameters::scalar(LocalModelKind::pi, HoldKind::zoh, 50, 0.9, 0.1, 0.5, 0.3 / 50), 400);
  EXPECT_NEAR(r.force, 0.9, 1e-9);   // K0 x_h
  EXPECT_NEAR(r.surface, 1.0, 1e-9); // no proxy offset
}

TEST(SteadyState, RingingAndDivergenceOfTheSeedExample) {
  const auto ring = analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, 0.2, 0, 0.19));
  EXPECT_NEAR(ring.poles.front().real(), -0.95, 1e-12);
  EXPECT_TRUE(ring.stable());
  EXPECT_FALSE(analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, 0.2, 0, 0.21)).stable());
  // It rings for seconds: 0.95^j falls below 2 % only after 77 frames (3.8 s at 20 Hz).
  EXPECT_GT(std::log(0.02) / std::log(0.95) * 0.05, 3.0);
}

TEST(CoupledContacts, EachAloneStableThePairNot) {
  LoopParameters pair;
  pair.local_model = LocalModelKind::p;
  pair.hold = HoldKind::zoh;
  pair.ratio = 50;
  pair.stiffness.resize(2, 2);
  pair.stiffness << 1, -0.8, -0.8, 1;
  pair.damping = Eigen::MatrixXd::Zero(2, 2);
  pair.gains = {0.3, 0};
  EXPECT_TRUE(analyse(LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 50, 1.0, 0, 0.3)).stable());
  const auto r = analyse(pair);
  EXPECT_FALSE(r.stable());
  // The soft mode (eigenvalue 0.2 of K0) has pole -Kh/0.2 = -1.5.
  EXPECT_NEAR(r.spectral_radius, 1.5, 1e-9);
  EXPECT_GT(simulated_growth(pair, 40), 1e3);
}

// The lifting holds the devices' loop's whole state: after any history (a device that wanders for
// a few frames, then stays still), the state read at consecutive frame boundaries of the running
// loop obeys X(j+1) = Phi X(j) for every local model and hold, two coupled contacts, a tissue that
// damps and a predictor whose model is off. A state the lifting missed (a slot, the tissue's
// memory) would break this after the wander.
TEST(Lifting, PredictsTheRunningLoopFrameByFrame) {
  Eigen::MatrixXd k0(2, 2), w(2, 2);
  k0 << 1.0, -0.3, -0.3, 0.8;
  w = 1.1 * k0.inverse();  // the predictor's model 10 % off
  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith})
    for (HoldKind hold : {HoldKind::zoh, HoldKind::foh}) {
      LoopParameters p;
      p.local_model = kind, p.hold = hold, p.ratio = 20;
      p.stiffness = k0, p.damping = 0.2 * k0, p.compliance = w;
      p.gains = {has_predictor(kind) ? 1.5 : 0.4, has_integrator(kind) ? 0.3 / 20 : 0.0};
      const StabilityResult lifted = analyse(p);
      NormalLoop loop(p);
      Eigen::VectorXd device(2);
      const int m = 2, size = (has_integrator(kind) ? 5 : 4) * m;
      const auto state = [&] {
        FrameBoundary b;
        loop.frame_boundary(b);
        Eigen::VectorXd x(size);
        x.segment(0, m) = b.answer_depth, x.segment(m, m) = b.newest_depth;
        x.segment(2 * m, m) = b.answer_force, x.segment(3 * m, m) = b.newest_force;
        if (has_integrator(kind)) x.tail(m) = b.integrator;
        return x;
      };
      for (int k = 0; k < 5 * p.ratio; ++k) {  // the wander
        device << 0.5 * std::sin(0.07 * k), 0.3 * std::cos(0.11 * k);
        loop.tick(device);
      }
      device.setZero();
      double worst = 0, largest = 0;
      for (int j = 0; j < 6; ++j) {
        const Eigen::VectorXd before = state();
        for (int i = 0; i < p.ratio; ++i) loop.tick(device);
        const Eigen::VectorXd after = state(), predicted = lifted.monodromy * before;
        worst = std::max(worst, (after - predicted).cwiseAbs().maxCoeff());
        largest = std::max(largest, after.cwiseAbs().maxCoeff());
      }
      EXPECT_GT(largest, 1e-3);
      EXPECT_LT(worst, 1e-12 * std::max(1.0, largest)) << to_string(kind) << " " << static_cast<int>(hold);
    }
}

}  // namespace
}  // namespace fetouch::haptics
