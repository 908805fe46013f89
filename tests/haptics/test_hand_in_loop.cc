// The lifting with the hand in the loop (stability_analysis.h, LoopParameters::hand): against its
// second implementation (scalar_loop.h), against Colgate's bound, and against the operator device
// pressing the linear loop in the time domain; and the gain selection with a design hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "haptics/devices.h"
#include "haptics/gain_selection.h"
#include "haptics/scalar_loop.h"
#include "haptics/stability_analysis.h"

namespace fetouch::haptics {
namespace {

constexpr double kPeriod = 1e-3;

HandParameters one_mass(double mass, double stiffness, double damping) {
  HandParameters hand;
  hand.mass_kg = mass, hand.stiffness_n_per_m = stiffness, hand.damping_n_s_per_m = damping;
  return hand;
}

// The general lifting (the devices' loop, normal_loop.h, with the hand stepped beside it) and the
// scalar tick recurrence are two implementations of one map: their radii agree for every local
// model, hold, ratio and hand model.
TEST(HandInTheLoop, LiftingAgreesWithTheScalarRecurrence) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0, 1);
  const LocalModelKind kinds[] = {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith};
  int unstable = 0;
  for (int trial = 0; trial < 160; ++trial) {
    ScalarLoop loop;
    loop.local_model = kinds[trial % 4];
    loop.hold = (trial / 4) % 2 ? HoldKind::foh : HoldKind::zoh;
    loop.ratio = 1 + trial % 60;
    loop.stiffness = 100 * std::pow(100, unit(random));
    loop.damping = 10 * unit(random);
    loop.compliance = 1 / (loop.stiffness * (0.7 + 0.6 * unit(random)));
    loop.gains = {loop.stiffness * unit(random), loop.stiffness * unit(random) / loop.ratio};
    HandParameters hand = one_mass(0.02 + 0.5 * unit(random), 200 + 2000 * unit(random), 8 * unit(random));
    if (trial % 3 == 0) hand.model = HandModelKind::stylus;
    LoopParameters p = LoopParameters::scalar(loop.local_model, loop.hold, loop.ratio, loop.stiffness, loop.damping,
                                              loop.gains.proportional, loop.gains.integral);
    p.compliance = Eigen::MatrixXd::Constant(1, 1, loop.compliance);
    p.hand = hand;
    const double general = analyse(p).spectral_radius;
    const double scalar = hand_spectral_radius(loop, ScalarHand(hand, kPeriod));
    unstable += general >= 1;
    EXPECT_NEAR(scalar, general, 1e-9 * std::max(1.0, general)) << "trial " << trial;
  }
  EXPECT_GT(unstable, 10);  // both sides of the boundary were tried
  EXPECT_LT(unstable, 150);
}

// Colgate & Schenkel's bound from the lifting: one tick per frame (N = 1), a tissue so stiff its
// surface does not move (the held surface stays at 0), so the P local model is a wall F = Kh x
// held over each tick, against a heavy hand (1 kg, b T / m <= 0.008, a grip spring of 1e-3 N/m):
// stable at 95 % of K = 2 b / T and not at 105 %. An answer independent of the simulation test in
// test_passivity.cc: eigenvalues of the lifted map against a closed-form bound.
TEST(HandInTheLoop, LiftingReproducesColgatesBound) {
  for (double b : {2.0, 5.0, 8.0}) {
    const double bound = 2 * b / kPeriod;
    SCOPED_TRACE("b " + std::to_string(b) + " N s/m, 2 b / T = " + std::to_string(bound) + " N/m");
    for (const auto& [share, stable] : {std::pair{0.95, true}, std::pair{1.05, false}}) {
      LoopParameters p = LoopParameters::scalar(LocalModelKind::p, HoldKind::zoh, 1, 1e12, 0, share * bound);
      p.hand = one_mass(1.0, 1e-3, b);
      EXPECT_EQ(analyse(p).spectral_radius < 1, stable) << "at " << share << " of the bound: radius " << analyse(p).spectral_radius;
    }
  }
}

// The verdict against the time domain: the linear multirate loop (make_loop) pressed by the
// operator device itself (devices.h, its own read/write), disturbed by an impact of 1 mm/s, grows
// where the lifting says the radius is over 1 and dies out where it is under. The device's
// position along -z is the penetration (the force pushes it back out along +z).
TEST(HandInTheLoop, VerdictMatchesTheOperatorPressingTheLinearLoop) {
  struct Case {
    LocalModelKind kind;
    HoldKind hold;
    double k0, kh, ni;
    HandParameters hand;
  };
  const double k0 = 23840;  // the 1 MPa block's condensed stiffness under a 5 mm probe
  const Case cases[] = {
      {LocalModelKind::pi, HoldKind::foh, k0, 5235, 7915, one_mass(0.3, 300, 8)},    // the proof without the hand's gains
      {LocalModelKind::pi, HoldKind::foh, k0, 5425, 3642, one_mass(0.3, 300, 8)},    // those with it
      {LocalModelKind::pi, HoldKind::foh, k0, 5425, 3642, one_mass(0.02, 2000, 0.5)},
      {LocalModelKind::p, HoldKind::zoh, 2384, 600, 0, one_mass(0.1, 1040, 2)},
      {LocalModelKind::p, HoldKind::zoh, 2384, 600, 0, one_mass(0.1, 1040, 8)},
      {LocalModelKind::smith, HoldKind::foh, k0, 27354, 0, stylus_hand()},
  };
  int grew = 0, died = 0;
  for (const Case& c : cases) {
    const int ratio = 50;
    LoopParameters p = LoopParameters::scalar(c.kind, c.hold, ratio, c.k0, 0, c.kh, c.ni / ratio);
    p.hand = c.hand;
    const double radius = analyse(p).spectral_radius;
    SCOPED_TRACE(std::string(to_string(c.kind)) + " + " + to_string(c.hold) + ", radius " + std::to_string(radius));
    ASSERT_GT(std::abs(radius - 1), 0.05) << "a case too close to the boundary to judge by a finite run";
    const long frames = 40, ticks = frames * ratio;
    Trajectory still;
    still.times_s = {0, ticks * kPeriod};
    still.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    HandEvent impact;
    impact.kind = HandEventKind::impact, impact.at_s = 0, impact.speed_m_per_s = 1e-3;
    VirtualOperator hand(still, c.hand, kPeriod, {impact});
    NormalLoop loop = make_loop(p);
    Eigen::VectorXd device(1);
    double early = 0, late = 0;
    for (long k = 0; k < ticks; ++k) {
      device(0) = -hand.read().position_m.z();
      const double force = loop.tick(device)(0);
      hand.write(Eigen::Vector3d(0, 0, force));
      const double size = std::abs(device(0));
      if (k >= ticks / 4 && k < ticks / 2) early = std::max(early, size);
      if (k >= 3 * ticks / 4) late = std::max(late, size);
    }
    // Ten frames apart: a radius r scales a mode by r^10 or so.
    if (radius > 1) {
      EXPECT_GT(late, 2 * early);
      ++grew;
    } else {
      EXPECT_LT(late, early);
      ++died;
    }
  }
  EXPECT_GE(grew, 2);
  EXPECT_GE(died, 2);
}

// The gain selection with a design hand: on a stiff tissue (the 1 MPa block) the gains the proof
// without the hand picks ring the default hand (the lifting with it says over 1); those picked
// with it as the design hand are stable with it at every scale of the uncertainty set and still
// robust without it. On a soft tissue (the default scene's 150 N/m) the hand asks nothing more.
TEST(HandInTheLoop, GainsSelectedWithTheDesignHandAreStableWithIt) {
  const HandParameters hand;  // the project's default: 0.3 kg, 300 N/m, 8 N s/m
  for (const auto& [kind, hold] : {std::pair{LocalModelKind::pi, HoldKind::foh}, std::pair{LocalModelKind::pi, HoldKind::zoh},
                                   std::pair{LocalModelKind::p, HoldKind::zoh}, std::pair{LocalModelKind::pi_smith, HoldKind::foh}}) {
    SCOPED_TRACE(std::string(to_string(kind)) + " + " + to_string(hold));
    GainProblem problem;
    problem.local_model = kind, problem.hold = hold, problem.ratio = 50;
    problem.stiffness = Eigen::MatrixXd::Constant(1, 1, 23840);
    GainSelectionOptions options;
    const GainSelection still = select_gains(problem, options);
    options.hand = hand;
    const GainSelection designed = select_gains(problem, options);
    ASSERT_TRUE(designed.stable);
    const auto radius_with_hand = [&](const LocalModelGains& gains, double scale) {
      LoopParameters p = LoopParameters::scalar(kind, hold, 50, scale * 23840, 0, gains.proportional, gains.integral);
      p.compliance = Eigen::MatrixXd::Constant(1, 1, 1 / 23840.0);
      p.hand = hand;
      return analyse(p).spectral_radius;
    };
    if (kind != LocalModelKind::p) {
      EXPECT_GT(radius_with_hand(still.gains, 1.0), 1.0);  // PI, PI + Smith ring it
    }
    for (double scale : {0.7, 0.85, 1.0, 1.15, 1.3}) {
      EXPECT_LT(radius_with_hand(designed.gains, scale), 1.0) << "scale " << scale;
      LoopParameters p = LoopParameters::scalar(kind, hold, 50, scale * 23840, 0, designed.gains.proportional, designed.gains.integral);
      p.compliance = Eigen::MatrixXd::Constant(1, 1, 1 / 23840.0);
      EXPECT_LT(analyse(p).spectral_radius, 1.0) << "scale " << scale << " without the hand";
    }
    // The selection's own figure: the worst over the set, so no better than the nominal scale's.
    EXPECT_GE(designed.hand_spectral_radius + 1e-12, radius_with_hand(designed.gains, 1.0));
    EXPECT_LT(designed.hand_spectral_radius, 1.0);
  }
  GainProblem soft;
  soft.local_model = LocalModelKind::pi, soft.hold = HoldKind::foh, soft.ratio = 50;
  soft.stiffness = Eigen::MatrixXd::Constant(1, 1, 150);
  GainSelectionOptions options;
  const GainSelection still = select_gains(soft, options);
  options.hand = hand;
  const GainSelection designed = select_gains(soft, options);
  EXPECT_NEAR(designed.gains.proportional, still.gains.proportional, 0.02 * still.gains.proportional);
  EXPECT_NEAR(designed.gains.integral, still.gains.integral, 0.02 * still.gains.integral);
}

}  // namespace
}  // namespace fetouch::haptics
