// The hand in the loop: Colgate's bound for a sampled wall, reproduced with the operator device, and
// the passivity layer (passivity.h) against its definition and against a wall that rings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <vector>

#include "haptics/devices.h"
#include "haptics/force_safety.h"
#include "haptics/passivity.h"

namespace fetouch::haptics {
namespace {

constexpr double kPeriod = 1e-3;

Trajectory still_at(const Eigen::Vector3d& point, double duration_s) {
  Trajectory t;
  t.times_s = {0, duration_s};
  t.positions_m = {point, point};
  return t;
}

// A bilateral wall F = -K x(k - d) - B (x(k - d) - x(k - d - 1)) / T on a hand of mass m and
// damping b (its grip spring 1e-3 N/m, nothing against K), kicked by 1 N at tick 0. Returns how the
// largest excursion of the last quarter compares with that of the second: < 1 decays, > 1 grows.
double wall_growth(double stiffness, double damping_b, int delay_ticks, double virtual_damping, long ticks = 20000) {
  VirtualOperator hand(still_at(Eigen::Vector3d::Zero(), ticks * kPeriod), HandParameters{1.0, 1e-3, damping_b}, kPeriod);
  std::deque<double> past(static_cast<std::size_t>(delay_ticks + 2), 0.0);
  double second_quarter = 0, last_quarter = 0;
  for (long k = 0; k < ticks; ++k) {
    const double x = hand.read().position_m.x();
    past.push_front(x);
    past.pop_back();
    const double delayed = past[delay_ticks], before = past[delay_ticks + 1];
    const double force = k == 0 ? 1.0 : -stiffness * delayed - virtual_damping * (delayed - before) / kPeriod;
    hand.write(Eigen::Vector3d(force, 0, 0));
    if (k > ticks / 4 && k < ticks / 2) second_quarter = std::max(second_quarter, std::abs(x));
    if (k > 3 * ticks / 4) last_quarter = std::max(last_quarter, std::abs(x));
  }
  return last_quarter / second_quarter;
}

// Colgate & Schenkel: a wall sampled at T is passive iff b > K T / 2 + |B|; with a delay t_d the
// limit becomes K < (b + B) / (T/2 + t_d) (Diolaiti et al. 2006). Passivity is sufficient for
// stability with any passive hand; for a heavy hand (m = 1 kg, b T / m <= 0.008) the stability
// limit of the sampled system approaches the passivity bound, so the wall must be stable at 95 % of
// it and unstable at 105 % (the 5 % the issue names; the exact limit is within 0.5 % here).
TEST(PassivityBound, SampledWallIsStableJustBelowColgatesBoundAndNotAbove) {
  for (double b : {2.0, 8.0})
    for (int delay : {0, 1, 2})
      for (double virtual_damping : {0.0, 0.25 * b}) {
        const double bound = (b + virtual_damping) / (kPeriod / 2 + delay * kPeriod);
        SCOPED_TRACE("b " + std::to_string(b) + " N s/m, delay " + std::to_string(delay) + " ticks, B " +
                     std::to_string(virtual_damping) + " N s/m, bound " + std::to_string(bound) + " N/m");
        EXPECT_LT(wall_growth(0.95 * bound, b, delay, virtual_damping), 1.0);
        EXPECT_GT(wall_growth(1.05 * bound, b, delay, virtual_damping), 1.0);
      }
}

// The observer's energy for a ZOH wall f(k) = -K x(k) along one axis is, by summation by parts,
//   E(n) = K sum x(k-1) (x(k) - x(k-1)) = K/2 (x(n)^2 - x(0)^2) - K/2 sum (x(k) - x(k-1))^2:
// the spring's energy less the hold's leak, exactly (to rounding).
TEST(PassivityObserver, WallEnergyIsTheSpringsLessTheHoldsLeak) {
  PassivitySettings settings;
  settings.mode = PassivityMode::observe;
  PassivityPort port(settings);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> step(-2e-4, 2e-4);
  const double stiffness = 3000;
  double x = 1e-3, leak = 0;
  const double x0 = x;
  for (int k = 0; k < 5000; ++k) {
    if (k > 0) {
      const double next = x + step(random);
      leak += 0.5 * stiffness * (next - x) * (next - x);
      x = next;
    }
    const Eigen::Vector3d force(-stiffness * x, 0, 0);
    EXPECT_TRUE(port.filter(Eigen::Vector3d(x, 0, 0), Eigen::Vector3d::Zero(), force).isApprox(force));
    port.sent(force);
  }
  const double expected = 0.5 * stiffness * (x * x - x0 * x0) - leak;
  EXPECT_NEAR(port.energy_j(), expected, 1e-12 + 1e-9 * std::abs(expected));
}

// A unilateral wall z < 0 of stiffness K, rendered through the layer and the safety layer, against a
// hand pulled `depth` into it. Forces per tick; the port is kept for its counters.
struct WallRun {
  std::vector<double> force;
  PassivityPort port;
  explicit WallRun(const PassivitySettings& s) : port(s) {}
};

WallRun press_wall(double stiffness, const HandParameters& hand_parameters, double depth, const PassivitySettings& settings,
                   double seconds = 2.0) {
  Trajectory path;
  path.times_s = {0, 0.2, seconds};
  path.positions_m = {Eigen::Vector3d(0, 0, 2e-3), Eigen::Vector3d(0, 0, -depth), Eigen::Vector3d(0, 0, -depth)};
  VirtualOperator hand(path, hand_parameters, kPeriod);
  ForceSafetyLimits limits;
  limits.max_force_n = 8.5;  // a Premium 1.5's, as in the ringing replay
  ForceSafety safety(limits);
  WallRun run(settings);
  while (!hand.finished()) {
    const DeviceState state = hand.read();
    const double penetration = std::max(0.0, -state.position_m.z());
    const Eigen::Vector3d requested(0, 0, stiffness * penetration);
    const Eigen::Vector3d sent = safety.filter(run.port.filter(state.position_m, state.velocity_m_per_s, requested), 0.0);
    run.port.sent(sent);
    hand.write(sent);
    run.force.push_back(sent.z());
  }
  return run;
}

// Peak to peak of the force over the last half second: a press that has settled holds still.
double last_swing(const std::vector<double>& force) {
  const auto tail = force.end() - 500;
  return *std::max_element(tail, force.end()) - *std::min_element(tail, force.end());
}

// The grip: light, stiff, barely damped (0.02 kg, 2000 N/m, 0.5 N s/m), on a wall of
// 5000 N/m, five times Colgate's 2 b / T = 1000 N/m. Left alone it rings at the clamp; with the
// scaling layer it settles where the hand's spring and the scaled wall share the pull,
// F = s K k d / (s K + k), s < 2 b / (T K). Hannaford and Ryu's damper, fed the same observer, cannot
// keep up with a wall this stiff against a hand this light: it rings on with controller forces far
// beyond any device's.
TEST(PassivityLayer, StopsAStiffWallRingingAgainstALightStiffGrip) {
  const HandParameters grip{0.02, 2000, 0.5};
  const double stiffness = 5000, depth = 1.5e-3;
  PassivitySettings off;
  off.mode = PassivityMode::observe;
  const WallRun ringing = press_wall(stiffness, grip, depth, off);
  EXPECT_GT(last_swing(ringing.force), 1.0) << "the wall alone must ring for this test to mean anything";
  EXPECT_LT(ringing.port.min_energy_j(), -1e-3) << "and the observer must see the energy it generates";

  const WallRun settled = press_wall(stiffness, grip, depth, PassivitySettings{});
  const double s = settled.port.scale();
  EXPECT_LT(s * stiffness, 2 * grip.damping_n_s_per_m / kPeriod);
  EXPECT_LT(last_swing(settled.force), 0.01);
  const double k = grip.stiffness_n_per_m, rest = s * stiffness * k * depth / (s * stiffness + k);
  EXPECT_NEAR(settled.force.back(), rest, 0.01 * rest);

  PassivitySettings baseline;
  baseline.controller = PassivityControllerKind::hannaford_ryu;
  const WallRun damped = press_wall(stiffness, grip, depth, baseline);
  EXPECT_GT(last_swing(damped.force), 1.0);
  EXPECT_GT(damped.port.max_controller_force_n(), 2 * settled.port.max_controller_force_n());
}

// The default hand on a wall inside Colgate's bound: the layer barely acts and changes nothing felt.
TEST(PassivityLayer, LeavesAStableContactAlone) {
  const HandParameters hand{0.3, 300, 8};
  const double stiffness = 2000, depth = 10e-3;
  PassivitySettings off;
  off.mode = PassivityMode::off;
  const WallRun free = press_wall(stiffness, hand, depth, off);
  const WallRun layered = press_wall(stiffness, hand, depth, PassivitySettings{});
  EXPECT_LE(layered.port.controller_ticks(), free.force.size() / 50);  // <= 2 % of ticks
  EXPECT_NEAR(layered.force.back(), free.force.back(), 0.05 * free.force.back());
}

// Whatever comes in, the scaling controller's force lies along the request and below it, steps by
// at most max_step_n (apart from the request's own change), and stays finite at zero velocity.
TEST(PassivityLayer, ControllerForceIsBoundedAndSmooth) {
  PassivitySettings settings;
  PassivityPort port(settings);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1, 1);
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double last_scale = 1;
  for (int k = 0; k < 20000; ++k) {
    position += 1e-3 * Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    const Eigen::Vector3d velocity =
        k % 7 == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    const Eigen::Vector3d requested = 5 * Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    const Eigen::Vector3d force = port.filter(position, velocity, requested);
    ASSERT_TRUE(force.allFinite());
    const double s = force.norm() / requested.norm();
    ASSERT_TRUE(force.isApprox(s * requested, 1e-12));
    ASSERT_LE(s, 1 + 1e-12);
    ASSERT_LE(std::abs(s - last_scale) * requested.norm(), settings.max_step_n + 1e-12);
    last_scale = s;
    port.sent(force);
  }
  EXPECT_GT(port.controller_ticks(), 0u) << "random motion against random forces generates energy";
}

// Four contacts of 50 ticks, each handing the hand 1.5e-5 J (1 N held while the device moves out
// by 0.3 um a tick), less than the allowance (2e-5 J) alone. A hand thrown off and back, 50 ms
// apart, is one contact bouncing: the bank carries over and runs dry at the second, and the
// stiffness is halved. Pokes 0.5 s apart are contacts of their own, each with its allowance.
double lowest_scale_over_contacts(long gap_ticks) {
  PassivityPort port{PassivitySettings{}};
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int contact = 0; contact < 4; ++contact) {
    for (int k = 0; k < 50; ++k) {
      position.z() += 3e-7;
      port.sent(port.filter(position, Eigen::Vector3d(0, 0, 3e-4), Eigen::Vector3d(0, 0, 1)));
    }
    for (long k = 0; k < gap_ticks; ++k) port.sent(port.filter(position, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  }
  return port.min_scale();
}

TEST(PassivityLayer, ABounceIsTheSameContactAndKeepsItsBank) {
  EXPECT_LT(lowest_scale_over_contacts(50), 0.75);  // halved (s on its way to 1/2)
  EXPECT_EQ(lowest_scale_over_contacts(500), 1.0);
}

// A press 5 mm into a spring of 2000 N/m (25 mJ in the port's bank), then a ring of 0.5 mm at 20 Hz
// about it under a force f = K d + c d' (d the depth, from where the contact began). With c < 0 the
// rendering hands the hand |c| pi w A^2 = 0.49 mJ a cycle: the bank, 50 cycles deep, would not
// see it for 2.5 s; the cycle books halve the stiffness within a few cycles. With c = 5 N s/m, more
// than the hold's leak K T / 2 = 1 N s/m, the ring is passive and nothing halves, and neither does a passive ring on a press that backs
// out at 4 mm/s (each cycle ends shallower, the store's change is not generation).
double scale_after_ring(double c, double drift_m_per_s, const PassivitySettings& settings = {}) {
  PassivityPort port(settings);
  const double stiffness = 2000, w = 2 * 3.14159265358979 * 20, amplitude = 5e-4;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * kPeriod;
    const double ring = t < 0.5 ? 0.0 : amplitude * std::sin(w * (t - 0.5));
    const double ring_rate = t < 0.5 ? 0.0 : amplitude * w * std::cos(w * (t - 0.5));
    const double depth = 1e-4 + (t < 0.5 ? 1e-2 * t : 5e-3 - drift_m_per_s * (t - 0.5)) + ring;
    const double rate = (t < 0.5 ? 1e-2 : -drift_m_per_s) + ring_rate;
    const Eigen::Vector3d position(0, 0, -depth), velocity(0, 0, -rate);
    const Eigen::Vector3d requested(0, 0, std::max(0.0, stiffness * depth + c * rate));
    port.sent(port.filter(position, velocity, requested));
  }
  return port.scale();
}

TEST(PassivityLayer, ARingAboutADeepPressIsCaughtByTheCycleNotTheBank) {
  EXPECT_LT(scale_after_ring(-5, 0), 0.3);  // halved twice or more in 0.5 s of ring
  PassivitySettings bank_only;
  bank_only.cycle_band_m = 1;  // no depth ever crosses: the bank alone
  EXPECT_EQ(scale_after_ring(-5, 0, bank_only), 1.0) << "the bank must miss it for this test to mean anything";
  EXPECT_EQ(scale_after_ring(5, 0), 1.0);
  EXPECT_EQ(scale_after_ring(5, 4e-3), 1.0);
}

TEST(PassivitySettings, RefusesValuesOutOfRange) {
  PassivitySettings s;
  s.max_step_n = 0;
  EXPECT_THROW(check(s), std::invalid_argument);
  s = PassivitySettings{};
  s.allowance_j = -1;
  EXPECT_THROW(check(s), std::invalid_argument);
  s = PassivitySettings{};
  s.bounce_gap_s = -0.1;
  EXPECT_THROW(check(s), std::invalid_argument);
  PassivityMode mode;
  EXPECT_TRUE(parse_passivity_mode("observe", mode));
  EXPECT_EQ(mode, PassivityMode::observe);
  EXPECT_FALSE(parse_passivity_mode("maybe", mode));
}

}  // namespace
}  // namespace fetouch::haptics
