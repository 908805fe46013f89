// Gain selection and the fast scalar evaluators it relies on, against independent answers: the
// general lifted analysis (which runs the Eigen loop itself), closed-form poles and simulation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "haptics/gain_selection.h"
#include "haptics/normal_loop.h"
#include "haptics/scalar_loop.h"
#include "haptics/stability_analysis.h"

namespace fetouch::haptics {
namespace {

using Pair = std::pair<LocalModelKind, HoldKind>;
const Pair kAllPairs[] = {
    {LocalModelKind::p, HoldKind::zoh},        {LocalModelKind::p, HoldKind::foh},
    {LocalModelKind::pi, HoldKind::zoh},       {LocalModelKind::pi, HoldKind::foh},
    {LocalModelKind::smith, HoldKind::zoh},    {LocalModelKind::smith, HoldKind::foh},
    {LocalModelKind::pi_smith, HoldKind::zoh}, {LocalModelKind::pi_smith, HoldKind::foh}};

TEST(CubicRoots, LargestModulusMatchesTheCompanionMatrix) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int t = 0; t < 20000; ++t) {
    const double a3 = u(rng) + (u(rng) > 0 ? 2.5 : -2.5), a2 = u(rng), a1 = u(rng), a0 = u(rng);
    const auto roots = polynomial_roots({a3, a2, a1, a0});
    double expected = 0;
    for (const auto& z : roots) expected = std::max(expected, std::abs(z));
    bool separated = true;  // repeated roots are only defined to ~sqrt(eps)
    for (size_t a = 0; a < roots.size(); ++a)
      for (size_t b = a + 1; b < roots.size(); ++b) separated = separated && std::abs(roots[a] - roots[b]) > 1e-3;
    if (!separated) continue;
    ASSERT_NEAR(cubic_max_root_modulus(a3, a2, a1, a0), expected, 1e-9 * std::max(1.0, expected))
        << a3 << " " << a2 << " " << a1 << " " << a0;
  }
}

ScalarLoop random_loop(Pair pair, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  ScalarLoop loop;
  loop.local_model = pair.first;
  loop.hold = pair.second;
  loop.ratio = 1 + static_cast<int>(u(rng) * 80);
  loop.stiffness = 0.05 + 2 * u(rng);
  loop.damping = u(rng) < 0.3 ? 0.0 : u(rng);
  // The predictor's compliance is off the true 1/k by up to 40 %, as under a stiffness margin.
  loop.compliance = (0.6 + 0.8 * u(rng)) / loop.stiffness;
  loop.gains.proportional = 2.5 * u(rng) - 0.3;
  loop.gains.integral = has_integrator(pair.first) ? (1.5 * u(rng) - 0.2) / loop.ratio : 0.0;
  return loop;
}

LoopParameters as_parameters(const ScalarLoop& s) {
  auto p = LoopParameters::scalar(s.local_model, s.hold, s.ratio, s.stiffness, s.damping,
                                  s.gains.proportional, s.gains.integral);
  p.compliance = Eigen::MatrixXd::Constant(1, 1, s.compliance);
  return p;
}

// The recurrence is a second implementation of the timing convention; the general analysis runs
// the loop's own Eigen code. 2,000 random sets per pair, all eight pairs.
TEST(ScalarRecurrence, AgreesWithTheGeneralAnalysisForEveryPair) {
  for (const Pair& pair : kAllPairs) {
    std::mt19937 rng(23);
    int compared = 0;
    for (int t = 0; t < 2000; ++t) {
      const ScalarLoop loop = random_loop(pair, rng);
      const double general = analyse(as_parameters(loop)).spectral_radius;
      const double compact = recurrence_spectral_radius(loop);
      // Defective or repeated eigenvalues are resolved only to ~eps^(1/k) by either method; the
      // tolerance 1e-6 covers double roots (sqrt(eps) ~ 1.5e-8 times the entries' scale) and
      // radii below 1e-3 (nilpotent, deadbeat-like maps) are skipped.
      if (general < 1e-3) continue;
      ++compared;
      ASSERT_NEAR(compact, general, 1e-6 * std::max(1.0, general))
          << static_cast<int>(pair.first) << "/" << static_cast<int>(pair.second) << " N " << loop.ratio
          << " k " << loop.stiffness << " b " << loop.damping << " w " << loop.compliance << " Kh "
          << loop.gains.proportional << " I " << loop.gains.integral;
    }
    EXPECT_GT(compared, 1900);
  }
}

TEST(ScalarRecurrence, ClosedFormsAgreeForPAndPi) {
  for (const Pair& pair : kAllPairs) {
    if (has_predictor(pair.first)) continue;
    std::mt19937 rng(29);
    for (int t = 0; t < 5000; ++t) {
      const ScalarLoop loop = random_loop(pair, rng);
      const double compact = recurrence_spectral_radius(loop), closed = scalar_spectral_radius(loop);
      if (closed < 1e-3) continue;
      ASSERT_NEAR(closed, compact, 1e-6 * std::max(1.0, closed));
    }
  }
}

GainProblem scalar_problem(Pair pair, double k0, double b0 = 0) {
  GainProblem problem;
  problem.local_model = pair.first;
  problem.hold = pair.second;
  problem.ratio = 50;
  problem.stiffness = Eigen::MatrixXd::Constant(1, 1, k0);
  problem.damping = Eigen::MatrixXd::Constant(1, 1, b0);
  return problem;
}

TEST(GainSelection, PiZohWithoutMarginFindsTheDeadbeatGains) {
  GainSelectionOptions exact;
  exact.margin = 0;
  const auto g = select_gains(scalar_problem({LocalModelKind::pi, HoldKind::zoh}, 2.0), exact);
  // Closed form: Kh = K0 and N I = K0 place both poles at 0. Near a double root the radius grows
  // like the square root of the distance, so gains within 1 % give a radius of a few percent.
  EXPECT_NEAR(g.gains.proportional, 2.0, 0.02);
  EXPECT_NEAR(50 * g.gains.integral, 2.0, 0.02);
  EXPECT_LT(g.spectral_radius, 0.1);
}

TEST(GainSelection, PZohTakesTheStiffestGainThatSettles) {
  // Pole -Kh/(s K0) with s in [0.7, 1.3]: the radius Kh/(0.7 K0) equals 0.5 at Kh = 0.35 K0.
  const auto g = select_gains(scalar_problem({LocalModelKind::p, HoldKind::zoh}, 4.0));
  EXPECT_NEAR(g.gains.proportional, 0.35 * 4.0, 0.35 * 4.0 * 2e-3);
  EXPECT_NEAR(g.spectral_radius, 0.5, 1e-3);
  EXPECT_TRUE(g.stable);
}

// For every pair: the chosen gains keep the loop stable for K0 anywhere in [0.7, 1.3] K0, checked by
// the general analysis on 31 stiffness values, with the predictor's compliance fixed at 1/K0.
TEST(GainSelection, ChosenGainsAreRobustlyStableForEveryPair) {
  for (const Pair& pair : kAllPairs)
    for (double b0 : {0.0, 0.2}) {
      const double k0 = 1.7;
      const auto g = select_gains(scalar_problem(pair, k0, b0));
      ASSERT_TRUE(g.stable);
      for (int j = 0; j <= 30; ++j) {
        const double s = 0.7 + 0.6 * j / 30;
        auto p = LoopParameters::scalar(pair.first, pair.second, 50, s * k0, b0, g.gains.proportional,
                                        g.gains.integral);
        p.compliance = Eigen::MatrixXd::Constant(1, 1, 1 / k0);
        EXPECT_LT(analyse(p).spectral_radius, 1.0)
            << static_cast<int>(pair.first) << "/" << static_cast<int>(pair.second) << " s " << s;
      }
    }
}

LoopParameters coupled_pair(const LocalModelGains& gains, double scale) {
  LoopParameters pair;
  pair.local_model = LocalModelKind::p;
  pair.hold = HoldKind::zoh;
  pair.ratio = 50;
  pair.stiffness.resize(2, 2);
  pair.stiffness << 1, -0.8, -0.8, 1;
  pair.stiffness *= scale;
  pair.damping = Eigen::MatrixXd::Zero(2, 2);
  pair.gains = gains;
  return pair;
}

TEST(GainSelection, CoupledPairIsTunedOnItsSoftMode) {
  GainProblem problem;
  problem.local_model = LocalModelKind::p;
  problem.hold = HoldKind::zoh;
  problem.stiffness = coupled_pair({}, 1).stiffness;
  // Kh = 0.3 is what each contact alone (K0 = 1) would accept; the pair's soft mode (0.2) does not.
  EXPECT_GT(robust_spectral_radius(problem, {0.3, 0}), 1.0);
  const auto g = select_gains(problem);
  ASSERT_TRUE(g.stable);
  EXPECT_LT(g.gains.proportional, 0.2 * 0.7);
  for (double s : {0.7, 1.0, 1.3}) {
    const auto p = coupled_pair(g.gains, s);
    EXPECT_LT(analyse(p).spectral_radius, 1.0) << s;
    // And a lockstep run of the pair, one contact pushed for a frame, decays.
    NormalLoop loop = make_loop(p);
    const Eigen::VectorXd push = Eigen::VectorXd::Unit(2, 0), still = Eigen::VectorXd::Zero(2);
    for (int k = 0; k < 50; ++k) loop.tick(push);
    double late = 0;
    for (int k = 0; k < 50 * 60; ++k) late = std::max(late, k > 50 * 55 ? loop.tick(still).norm() : (loop.tick(still), 0.0));
    EXPECT_LT(late, 1e-6) << s;
  }
}

TEST(GainSelection, RejectsStiffnessThatIsNotPositiveDefinite) {
  GainProblem problem;
  problem.stiffness.resize(2, 2);
  problem.stiffness << 1, 2, 2, 1;  // eigenvalues 3 and -1
  EXPECT_THROW(select_gains(problem), std::invalid_argument);
  problem.stiffness << 1, 0.5, 0.4, 1;
  EXPECT_THROW(select_gains(problem), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::haptics
