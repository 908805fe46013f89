// The conforming mesher's grid fields (meshes/label_fields.h) against closed forms: the chamfer
// grading's distances along the axes and diagonals from one fine voxel, and the indicator biases
// checked by moving each surface by the bias difference over the slope and adding up the volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "meshes/label_fields.h"

namespace fetouch::meshes {
namespace {

TEST(LabelFields, GradingGrowsFromAFineVoxelByTheGradingTimesTheDistance) {
  GridField f;
  f.n = {21, 21, 21};
  f.h = {1.0, 2.0, 0.5};  // anisotropic voxels, mm
  f.v.assign(21 * 21 * 21, 100.f);
  f.v[std::size_t((10 * 21 + 10) * 21 + 10)] = 1.f;
  grade(f, 0.3);
  // Along an axis and along the 26-neighbourhood's diagonals the chamfer distance is exact.
  for (int k = 0; k <= 10; ++k) {
    EXPECT_NEAR(f.at(10 + k, 10, 10), 1 + 0.3 * k * 1.0, 1e-5);
    EXPECT_NEAR(f.at(10, 10 - k, 10), 1 + 0.3 * k * 2.0, 1e-5);
    EXPECT_NEAR(f.at(10, 10, 10 + k), 1 + 0.3 * k * 0.5, 1e-5);
    EXPECT_NEAR(f.at(10 - k, 10 + k, 10 - k), 1 + 0.3 * k * std::sqrt(1.0 + 4.0 + 0.25), 1e-4);
  }
  // Nowhere grows faster than the grading (a Lipschitz bound over every neighbour pair), and a
  // coarse voxel far enough away keeps its own size.
  EXPECT_FLOAT_EQ(f.at(0, 0, 0), std::min(100.0, 1 + 0.3 * std::sqrt(100.0 + 400.0 + 25.0)));
  for (int k = 0; k + 1 < 21; ++k)
    for (int j = 0; j < 21; ++j)
      for (int i = 0; i < 21; ++i) EXPECT_LE(std::abs(f.at(i, j, k + 1) - f.at(i, j, k)), 0.3 * 0.5 + 1e-5);
}

// The volume each region gains when every surface between r and q moves by (b_r - b_q) / slope.
std::vector<double> gained(const std::map<std::pair<int, int>, double>& between, const std::vector<double>& bias,
                           double slope) {
  std::vector<double> g(bias.size(), 0.0);
  for (const auto& [pair, a] : between) {
    const auto [r, q] = pair;
    g[std::size_t(r)] += a * (bias[std::size_t(r)] - bias[std::size_t(q)]) / slope;
    g[std::size_t(q)] += a * (bias[std::size_t(q)] - bias[std::size_t(r)]) / slope;
  }
  return g;
}

TEST(LabelFields, BiasesGiveEachRegionTheVolumeItLacks) {
  // A core (1) inside a shell (2) inside the background, a third region (3) touching the shell
  // and the background, and a fourth (4) with no surface at all.
  const std::map<std::pair<int, int>, double> between = {{{0, 2}, 900.0}, {{1, 2}, 300.0}, {{2, 3}, 50.0}, {{0, 3}, 120.0}};
  const std::vector<double> missing = {0.0, -4.0, 12.0, 3.0, 7.0};
  const double slope = 0.33;
  const std::vector<double> bias = volume_biases(between, missing, slope, std::vector<double>(5, 0.0));
  ASSERT_EQ(bias.size(), 5u);
  EXPECT_EQ(bias[0], 0.0);
  EXPECT_EQ(bias[4], 0.0);  // nothing to move
  const std::vector<double> g = gained(between, bias, slope);
  for (int r = 1; r <= 3; ++r) EXPECT_NEAR(g[std::size_t(r)], missing[std::size_t(r)], 1e-9) << "region " << r;
  // One region against the background alone: b = missing slope / area, clamped to 0.25.
  EXPECT_NEAR(volume_biases({{{0, 1}, 100.0}}, {0.0, 5.0}, 0.4, {0.0, 0.0})[1], 0.02, 1e-15);
  EXPECT_EQ(volume_biases({{{0, 1}, 1.0}}, {0.0, 500.0}, 0.4, {0.0, 0.0})[1], 0.25);
  EXPECT_EQ(volume_biases({{{0, 1}, 1.0}}, {0.0, -500.0}, 0.4, {0.0, 0.0})[1], -0.25);
}

}  // namespace
}  // namespace fetouch::meshes
