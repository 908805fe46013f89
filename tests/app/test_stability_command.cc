// `fetouch stability` against the closed forms of ARCHITECTURE.md section 3.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

TEST(StabilityCommand, ProportionalZohMatchesTheClosedForm) {
  const auto r = run_command(fetouch("stability --json --local-model p --k0 0.9 --kh 0.1"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_NEAR(j["spectral_radius"].as<double>(), 0.1 / 0.9, 1e-12);  // |B0 - Kh| / (K0 + B0)
  EXPECT_NEAR(j["steady_force"].as<double>(), 0.9 * 0.1 / 1.0, 1e-12);
  EXPECT_NEAR(j["steady_proxy_offset"].as<double>(), 0.9, 1e-12);
  EXPECT_TRUE(j["stable"].as<bool>());
}

TEST(StabilityCommand, RingingSettlesSlowlyAndDivergenceExitsOne) {
  const auto ring = run_command(fetouch("stability --json --local-model p --k0 0.2 --kh 0.19"));
  ASSERT_EQ(ring.exit_code, 0);
  // Pole -0.95: the error falls below 2 % after ceil(ln 0.02 / ln 0.95) = 77 frames of 50 ms.
  EXPECT_NEAR(YAML::Load(ring.out)["force_settling_s"].as<double>(), 77 * 0.05, 0.05 + 1e-9);
  const auto diverge = run_command(fetouch("stability --local-model p --k0 0.2 --kh 0.21"));
  EXPECT_EQ(diverge.exit_code, 1);
  EXPECT_NE(diverge.out.find("UNSTABLE"), std::string::npos);
}

// --hand against Colgate's bound: one tick a frame (-N 1), a tissue whose surface does not move, a
// P wall against a 1 kg hand with 5 N s/m: stable at 95 % of 2 b / T = 10,000 N/m, not at 105 %,
// while the loop without the hand (the device held still) is stable at both.
TEST(StabilityCommand, WithAHandItReproducesColgatesBound) {
  const auto below = run_command(fetouch("stability --json --local-model p -N 1 --k0 1e12 --kh 9500 --hand 1 0.001 5"));
  ASSERT_EQ(below.exit_code, 0) << below.err;
  const YAML::Node b = YAML::Load(below.out);
  EXPECT_TRUE(b["stable"].as<bool>());
  EXPECT_TRUE(b["stable_with_hand"].as<bool>());
  EXPECT_LT(b["spectral_radius_with_hand"].as<double>(), 1);
  const auto above = run_command(fetouch("stability --json --local-model p -N 1 --k0 1e12 --kh 10500 --hand 1 0.001 5"));
  EXPECT_EQ(above.exit_code, 1);
  const YAML::Node a = YAML::Load(above.out);
  EXPECT_TRUE(a["stable"].as<bool>());
  EXPECT_FALSE(a["stable_with_hand"].as<bool>());
  const auto text = run_command(fetouch("stability --local-model p -N 1 --k0 1e12 --kh 10500 --hand 1 0.001 5"));
  EXPECT_NE(text.out.find("the loop with this hand in it rings"), std::string::npos) << text.out;
  EXPECT_EQ(run_command(fetouch("stability --local-model p --hand 0 300 8")).exit_code, 2);  // no mass
}

TEST(StabilityCommand, BadInputExitsTwo) {
  EXPECT_EQ(run_command(fetouch("stability --local-model q")).exit_code, 2);
  EXPECT_EQ(run_command(fetouch("stability --k0 -1")).exit_code, 2);
  EXPECT_EQ(run_command(fetouch("stability --local-model p --ni 0.3")).exit_code, 2);
}

}  // namespace
}  // namespace fetouch::testing
