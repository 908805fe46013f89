// The safety layer against its definition (force_safety.h): every output finite, inside the ball of
// radius F_max, changing by at most R T per tick, and faded to zero by the watchdog.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/force_safety.h"

namespace fetouch::haptics {
namespace {

ForceSafetyLimits limits() {
  ForceSafetyLimits l;
  l.max_force_n = 3.0;
  l.max_force_rate_n_per_s = 1000;  // 1 N per 1 ms tick
  l.period_s = 1e-3;
  l.watchdog_timeout_s = 0.1;
  l.watchdog_fade_s = 0.05;
  return l;
}

TEST(ForceSafety, PassesSmallSlowForcesUnchanged) {
  ForceSafety safety(limits());
  const Eigen::Vector3d f(0.3, -0.4, 0.5);
  EXPECT_TRUE(safety.filter(f, 0.0).isApprox(f));
  EXPECT_EQ(safety.clamped_ticks() + safety.rate_limited_ticks(), 0u);
}

TEST(ForceSafety, ClampsMagnitudeKeepingDirection) {
  ForceSafety safety(limits());
  const Eigen::Vector3d request(30, 40, 0);  // 50 N along (0.6, 0.8, 0)
  Eigen::Vector3d out;
  for (int k = 0; k < 20; ++k) out = safety.filter(request, 0.0);
  EXPECT_NEAR(out.norm(), 3.0, 1e-12);
  EXPECT_NEAR(out.x() / out.norm(), 0.6, 1e-12);
}

TEST(ForceSafety, RateLimitsSteps) {
  ForceSafety safety(limits());
  // A 2 N step reaches its value in two ticks of 1 N.
  EXPECT_NEAR(safety.filter({0, 0, 2}, 0.0).z(), 1.0, 1e-12);
  EXPECT_NEAR(safety.filter({0, 0, 2}, 0.0).z(), 2.0, 1e-12);
}

TEST(ForceSafety, NonFiniteRequestsBecomeZero) {
  ForceSafety safety(limits());
  safety.filter({0, 0, 0.5}, 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d out = safety.filter({nan, 0, 1}, 0.0);
  EXPECT_TRUE(out.allFinite());
  EXPECT_NEAR(out.norm(), 0.0, 1e-12);
  EXPECT_EQ(safety.non_finite_ticks(), 1u);
  EXPECT_TRUE(safety.filter({0, 0, std::numeric_limits<double>::infinity()}, nan).allFinite());
}

TEST(ForceSafety, WatchdogFadesLinearlyToZero) {
  ForceSafety safety(limits());
  const Eigen::Vector3d f(0, 0, 0.8);
  EXPECT_NEAR(safety.filter(f, 0.1).z(), 0.8, 1e-12);     // at the timeout: full force
  EXPECT_NEAR(safety.filter(f, 0.125).z(), 0.4, 1e-12);   // half way through the fade
  EXPECT_NEAR(safety.filter(f, 0.15).z(), 0.0, 1e-12);    // faded out
  EXPECT_NEAR(safety.filter(f, 10.0).z(), 0.0, 1e-12);
  EXPECT_EQ(safety.watchdog_ticks(), 3u);
}

// A stopping session's ramp out: with R = 4 a steady 0.8 N request is sent as 0.6, 0.4, 0.2, 0
// (h = 1 - (k - k0 + 1) / R), then stays 0; asking again restarts nothing.
TEST(ForceSafety, RampOutFadesLinearlyToZeroAndStaysThere) {
  ForceSafety safety(limits());
  const Eigen::Vector3d f(0, 0.8, 0);
  EXPECT_NEAR(safety.filter(f, 0.0).y(), 0.8, 1e-12);
  EXPECT_FALSE(safety.ramping_out());
  safety.ramp_out(4);
  EXPECT_TRUE(safety.ramping_out());
  for (double expected : {0.6, 0.4, 0.2}) {
    EXPECT_NEAR(safety.filter(f, 0.0).y(), expected, 1e-12);
    EXPECT_FALSE(safety.ramped_out());
    safety.ramp_out(100);
  }
  EXPECT_EQ(safety.filter(f, 0.0).norm(), 0.0);
  EXPECT_TRUE(safety.ramped_out());
  EXPECT_EQ(safety.filter(Eigen::Vector3d(2, 0, 0), 0.0).norm(), 0.0);
}

TEST(ForceSafety, InvariantsHoldOnRandomRequests) {
  ForceSafety safety(limits());
  std::mt19937 rng(7);
  std::normal_distribution<double> force(0, 10);
  std::uniform_real_distribution<double> age(0, 0.2);
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int k = 0; k < 100000; ++k) {
    const Eigen::Vector3d out = safety.filter({force(rng), force(rng), force(rng)}, age(rng));
    ASSERT_TRUE(out.allFinite());
    ASSERT_LE(out.norm(), 3.0 + 1e-12);
    ASSERT_LE((out - previous).norm(), 1.0 + 1e-12);
    previous = out;
  }
}

}  // namespace
}  // namespace fetouch::haptics
