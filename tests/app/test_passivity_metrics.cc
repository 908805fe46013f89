// The passivity study's judge (app/study/passivity_metrics.h) on signals whose answer is known: a
// steady ring well above tremor is oscillation, physiological tremor is not, a ring that dies out
// is not, one that grows is, and a force jumping between nothing and the clamp is chatter. The felt
// stiffness of a linear spring pressed along any direction is its constant. The ideal tissue (a
// flat elastic wall in continuous time) against closed forms: the static press of a hand's spring
// in series with the wall, and an elastic impact's impulse 2 m v and peak force v sqrt(m K); and
// bounces count against the loop only beyond the ideal tissue's.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "app/study/passivity_metrics.h"

namespace fetouch::app {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kT = 1e-3;

// 2 s at 1 kHz: 2 N held, plus amplitude a(t) sin(2 pi f t) from 0.5 s on.
std::vector<double> held_with(double frequency_hz, double amplitude_n, double growth_per_s) {
  std::vector<double> f(2000);
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double t = k * kT;
    f[k] = 2.0 + (t < 0.5 ? 0.0 : amplitude_n * std::exp(growth_per_s * (t - 0.5)) * std::sin(2 * kPi * frequency_hz * (t - 0.5)));
  }
  return f;
}

// A force of `peak` in half-sine humps of `hump_s`, each after a gap of `gap_s` (0 N), `count` of
// them from 0.2 s on, in 3 s at 1 kHz.
std::vector<double> humps(int count, double hump_s, double gap_s, double peak) {
  std::vector<double> f(3000, 0.0);
  double start = 0.2;
  for (int h = 0; h < count; ++h, start += hump_s + gap_s)
    for (std::size_t k = 0; k < f.size(); ++k) {
      const double t = k * kT - start;
      if (t > 0 && t < hump_s) f[k] = peak * std::sin(kPi * t / hump_s);
    }
  return f;
}

// The hand thrown off a stiff tissue and back at a few hertz (what a 0.57 kg hand on a 230 N/m,
// 0.5 N s/m grip does on the 1 MPa block under PI: humps up to the clamp, 0.1 s on, 0.1 s off)
// oscillates, though its force rises over tens of ticks (no chatter) and below 90 Hz (no ring).
TEST(PassivityMetrics, AHandBouncingOffTheTissueOscillates) {
  const Oscillation o = detect_oscillation(humps(10, 0.1, 0.1, 8.5), kT, 8.5);
  EXPECT_EQ(o.chatter_ticks, 0);
  EXPECT_LT(o.ringing_s, 0.3);
  EXPECT_EQ(o.bounces, 9);
  EXPECT_TRUE(o.oscillates);
  // Two pokes of a trajectory half a second apart, and one rebound after an impact, do not.
  EXPECT_FALSE(detect_oscillation(humps(2, 0.8, 0.5, 8.5), kT, 8.5).oscillates);
  EXPECT_EQ(detect_oscillation(humps(2, 0.05, 0.02, 3), kT, 8.5).bounces, 1);
  EXPECT_FALSE(detect_oscillation(humps(2, 0.05, 0.02, 3), kT, 8.5).oscillates);
  // Bounces too light to count (under 10 % of the clamp: a hand grazing the surface) do not either.
  EXPECT_EQ(detect_oscillation(humps(10, 0.1, 0.1, 0.5), kT, 8.5).bounces, 0);
}

TEST(PassivityMetrics, AFortyHertzRingOfAFewTenthsOfANewtonOscillates) {
  // The 11-tick mean passes 71 % of a 40 Hz sine: 0.3 N leaves 0.17 N peak to peak above 0.1 N.
  const Oscillation o = detect_oscillation(held_with(40, 0.3, 0), kT, 8.5);
  EXPECT_TRUE(o.oscillates);
  EXPECT_NEAR(o.ringing_s, 1.45, 0.06);  // from 0.5 s to the last whole window before the end
  EXPECT_NEAR(o.ringing_ptp_n, 2 * 0.3 * (1 - std::sin(11 * 2 * kPi * 40 * kT / 2) / (11 * std::sin(2 * kPi * 40 * kT / 2))), 0.02);
}

TEST(PassivityMetrics, PhysiologicalTremorIsNotOscillation) {
  // A 12 Hz tremor of 1 N: the 11-tick mean keeps 97 % of it; what is left swings 0.06 N (only
  // the window where it starts, a kink, may swing a little more).
  for (double f : {6.0, 8.0, 10.0, 12.0}) {
    const Oscillation o = detect_oscillation(held_with(f, 1.0, 0), kT, 8.5);
    EXPECT_FALSE(o.oscillates) << f << " Hz";
    EXPECT_LE(o.ringing_s, 0.05 + 1e-9) << f << " Hz";
  }
}

// A zero-order hold's staircase: a press whose held surface steps once a 50 ms frame, the force
// jumping 0.3 N at each step (more than ringing_n after the moving average) for 1.5 s. It swings,
// but once a window, never back and forth: no ring. The same steps with a 150 Hz ring of 0.1 N on
// them do ring.
TEST(PassivityMetrics, AZeroOrderHoldsFrameStepsAreNotARing) {
  std::vector<double> steps(2000, 0.0), ringing(2000, 0.0);
  for (std::size_t k = 0; k < steps.size(); ++k) {
    steps[k] = 1.0 + 0.3 * std::min<std::size_t>(k / 50, 30);
    ringing[k] = steps[k] + (k > 200 ? 0.1 * std::sin(2 * kPi * 150 * k * kT) : 0.0);
  }
  const Oscillation staircase = detect_oscillation(steps, kT, 20);
  EXPECT_GT(staircase.ringing_ptp_n, 0.1) << "the steps must swing for this test to mean anything";
  EXPECT_EQ(staircase.ringing_s, 0.0);
  EXPECT_FALSE(staircase.oscillates);
  EXPECT_TRUE(detect_oscillation(ringing, kT, 20).oscillates);
}

TEST(PassivityMetrics, ARingThatDiesOutIsNotOscillationAndOneThatGrowsIs) {
  // 2 N at 60 Hz, halving every 35 ms: loud, but gone well within 0.3 s.
  EXPECT_FALSE(detect_oscillation(held_with(60, 2.0, -std::log(2.0) / 0.035), kT, 8.5).oscillates);
  // 0.05 N growing by e every 0.2 s: small at first, the loop's own ring.
  const Oscillation grows = detect_oscillation(held_with(60, 0.05, 5), kT, 1000);
  EXPECT_TRUE(grows.oscillates);
  EXPECT_EQ(grows.chatter_ticks, 0);
}

TEST(PassivityMetrics, AForceJumpingBetweenNothingAndTheClampChatters) {
  std::vector<double> f(1000, 0.0);
  for (std::size_t k = 300; k < 320; ++k) f[k] = (k / 2) % 2 ? 8.5 : 0.0;  // two ticks each, 20 ticks long
  const Oscillation o = detect_oscillation(f, kT, 8.5);
  EXPECT_GE(o.chatter_ticks, 10);
  EXPECT_TRUE(o.oscillates);
  // A single contact that rises to the clamp over 20 ticks is not chatter.
  std::vector<double> rise(1000, 0.0);
  for (std::size_t k = 300; k < 1000; ++k) rise[k] = std::min(8.5, 8.5 * (k - 300) / 20.0);
  EXPECT_EQ(detect_oscillation(rise, kT, 8.5).chatter_ticks, 0);
}

TEST(PassivityMetrics, FeltStiffnessOfALinearSpringIsItsConstant) {
  const double k = 1234.5;
  const Eigen::Vector3d press = Eigen::Vector3d(0.3, -0.2, -0.9).normalized();
  const Eigen::Vector3d start(0.01, 0.02, 0.05);
  std::vector<Eigen::Vector3d> forces, positions;
  // Approach (no force), press in 8 mm over 500 ticks, hold, come back out.
  for (int i = 0; i < 1500; ++i) {
    const double depth = i < 200 ? 0.0 : i < 700 ? 8e-3 * (i - 200) / 500.0 : i < 1000 ? 8e-3 : 8e-3 * (1500 - i) / 500.0;
    const Eigen::Vector3d sideways = 1e-3 * std::sin(0.01 * i) * press.unitOrthogonal();  // no force across the press
    const Eigen::Vector3d approach = i < 200 ? Eigen::Vector3d((200 - i) * 1e-5 * press) : Eigen::Vector3d::Zero();
    positions.push_back(start + depth * press + sideways - approach);
    forces.push_back(i < 201 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(-k * depth * press));
  }
  EXPECT_NEAR(felt_stiffness(forces, positions), k, 1e-6 * k);
  EXPECT_TRUE(std::isnan(felt_stiffness(std::vector<Eigen::Vector3d>(10, Eigen::Vector3d::Zero()), positions)));
}

// A trajectory of straight segments through (t, z) points at x = y = 0.
haptics::Trajectory along_z(const std::vector<std::pair<double, double>>& points) {
  haptics::Trajectory path;
  for (const auto& [t, z] : points) path.times_s.push_back(t), path.positions_m.emplace_back(0, 0, z);
  return path;
}

// The hand's spring in series with the wall: pressed d behind it, the force settles to
// k K / (k + K) d.
TEST(IdealWall, AStaticPressIsTheHandsSpringInSeriesWithTheWall) {
  haptics::HandParameters hand;  // 0.3 kg, 300 N/m, 8 N s/m
  IdealWall wall;
  wall.point = Eigen::Vector3d::Zero(), wall.normal = Eigen::Vector3d::UnitZ();
  wall.stiffness_n_per_m = 2e4, wall.clamp_n = 100;
  const double depth = 8e-3;
  const std::vector<double> f = ideal_wall_forces(along_z({{0, 0.01}, {0.5, -depth}, {3, -depth}}), hand, {}, wall, kT);
  ASSERT_EQ(f.size(), 3001u);  // as the session runs it: a tick from 0 s to 3 s inclusive
  const double expected = hand.stiffness_n_per_m * wall.stiffness_n_per_m / (hand.stiffness_n_per_m + wall.stiffness_n_per_m) * depth;
  EXPECT_NEAR(f.back(), expected, 1e-3 * expected);
  EXPECT_EQ(f[100], 0.0);  // 8 mm in front of the wall at 0.1 s
  // Behind a clamp under that force, the force is the clamp.
  wall.clamp_n = 1;
  EXPECT_NEAR(ideal_wall_forces(along_z({{0, 0.01}, {0.5, -depth}, {3, -depth}}), hand, {}, wall, kT).back(), 1.0, 1e-12);
}

// A hand struck towards the wall at v with no damping and a negligible spring: the contact is half
// a period of m on K, its impulse 2 m v and its peak v sqrt(m K) (Hertz's linear case).
TEST(IdealWall, AnElasticImpactHasTheClosedFormImpulseAndPeak) {
  haptics::HandParameters hand;
  hand.mass_kg = 0.2, hand.stiffness_n_per_m = 1e-3, hand.damping_n_s_per_m = 0;
  IdealWall wall;
  wall.point = Eigen::Vector3d::Zero(), wall.normal = Eigen::Vector3d::UnitZ();
  wall.stiffness_n_per_m = 2e4, wall.clamp_n = 1e3;
  haptics::HandEvent strike;
  strike.kind = haptics::HandEventKind::impact, strike.at_s = 0.1, strike.speed_m_per_s = 0.2;
  strike.direction = -Eigen::Vector3d::UnitZ();
  const std::vector<double> f = ideal_wall_forces(along_z({{0, 1e-3}, {0.5, 1e-3}}), hand, {strike}, wall, kT);
  double impulse = 0, peak = 0;
  long contacts = 0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    impulse += f[k] * kT, peak = std::max(peak, f[k]);
    contacts += f[k] > 0 && (k == 0 || f[k - 1] == 0);
  }
  EXPECT_EQ(contacts, 1);  // it flies back and stays away
  EXPECT_NEAR(impulse, 2 * hand.mass_kg * 0.2, 0.01 * 2 * hand.mass_kg * 0.2);
  const double apex = 0.2 * std::sqrt(hand.mass_kg * wall.stiffness_n_per_m);
  EXPECT_NEAR(peak, apex, 0.03 * apex);  // a tick's mean near the apex
  EXPECT_LE(peak, apex * (1 + 1e-6));
}

TEST(IdealWall, ItIsPlacedWhereTheForceFirstRoseFacingIt) {
  std::vector<Eigen::Vector3d> forces(5, Eigen::Vector3d::Zero()), positions;
  for (int k = 0; k < 5; ++k) positions.emplace_back(0, 0, 0.01 - 1e-3 * k);
  forces[3] = Eigen::Vector3d(0, 3, 4), forces[4] = Eigen::Vector3d(0, 6, 8);
  const std::optional<IdealWall> wall = wall_at_first_touch(forces, positions, 5e3, 8.5);
  ASSERT_TRUE(wall);
  EXPECT_EQ(wall->point, positions[2]);
  EXPECT_NEAR((wall->normal - Eigen::Vector3d(0, 0.6, 0.8)).norm(), 0, 1e-12);
  EXPECT_EQ(wall->stiffness_n_per_m, 5e3);
  EXPECT_FALSE(wall_at_first_touch(std::vector<Eigen::Vector3d>(5, Eigen::Vector3d::Zero()), positions, 5e3, 8.5));
}

// Five bounces where the ideal tissue makes three are two too few to blame the loop; where it
// makes one they are the loop's. Ringing and chatter are the loop's whatever the ideal does.
TEST(PassivityMetrics, BouncesCountOnlyBeyondTheIdealTissues) {
  const Oscillation five = detect_oscillation(humps(6, 0.1, 0.1, 8.5), kT, 8.5);
  ASSERT_EQ(five.bounces, 5);
  ASSERT_TRUE(five.oscillates);
  Oscillation ideal;
  ideal.bounces = 3;
  EXPECT_FALSE(judge_against_ideal(five, ideal).oscillates);
  EXPECT_EQ(judge_against_ideal(five, ideal).ideal_bounces, 3);
  ideal.bounces = 2;
  EXPECT_TRUE(judge_against_ideal(five, ideal).oscillates);
  Oscillation ring;
  ring.ringing_s = 0.5;
  ideal.bounces = 0, ideal.ringing_s = 1.0;
  EXPECT_TRUE(judge_against_ideal(ring, ideal).oscillates);
  Oscillation chatter;
  chatter.chatter_ticks = 3;
  EXPECT_TRUE(judge_against_ideal(chatter, ideal).oscillates);
}

}  // namespace
}  // namespace fetouch::app
