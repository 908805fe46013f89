// Filters and segmentation against closed forms (a Gaussian's second moment, a hollow ball's volume,
// Dice of known overlaps) and on the synthetic phantom: the fetus segmented from the speckled image
// against the phantom's ground truth, Dice >= 0.9.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "imaging/phantom.h"
#include "imaging/segmentation.h"

namespace fetouch::imaging {
namespace {

template <class T>
Volume<T> cube(int n, double spacing = 1) {
  Volume<T> v;
  v.dimensions = {n, n, n};
  v.spacing_mm = {spacing, spacing, spacing};
  v.data.assign(std::size_t(n) * n * n, T{});
  return v;
}

TEST(Segmentation, GaussianKeepsTheMeanAndHasItsSecondMoment) {
  // Far enough from the faces that the kernel's renormalisation there plays no part.
  auto v = cube<float>(61, 0.5);
  v.data[v.index(30, 30, 30)] = 1000;
  const auto s = gaussian_smooth(v, 2.0);  // sigma 4 voxels, truncated at 3 sigma
  double total = 0, moment = 0;
  for (int i = 0; i < 61; ++i) {
    const double value = s.data[s.index(i, 30, 30)];
    total += value, moment += value * (i - 30) * (i - 30);
  }
  // A Gaussian truncated at 3 sigma has variance sigma^2 (1 - 6 phi(3) / (2 Phi(3) - 1)) = 15.57.
  EXPECT_NEAR(moment / total, 16.0 * (1 - 6 * 0.0044318 / 0.9973), 0.2);
  double sum = 0;
  for (float x : s.data) sum += x;
  EXPECT_NEAR(sum, 1000, 1e-2);
}

TEST(Segmentation, MedianRemovesASpeckAndKeepsAnEdge) {
  auto v = cube<float>(9);
  for (int k = 0; k < 9; ++k)
    for (int j = 0; j < 9; ++j)
      for (int i = 5; i < 9; ++i) v.data[v.index(i, j, k)] = 100;
  v.data[v.index(2, 4, 4)] = 255;
  const auto m = median3(v);
  EXPECT_EQ(m.data[m.index(2, 4, 4)], 0.0f);
  EXPECT_EQ(m.data[m.index(5, 4, 4)], 100.0f);
  EXPECT_EQ(m.data[m.index(4, 4, 4)], 0.0f);
}

TEST(Segmentation, ComponentsClosingAndHoleFilling) {
  auto mask = cube<std::uint8_t>(30);
  // A hollow ball (radii 6 and 10) in the middle, a small block touching a face.
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) {
        const double r = std::sqrt((i - 15.0) * (i - 15.0) + (j - 15.0) * (j - 15.0) + (k - 15.0) * (k - 15.0));
        if (r <= 10 && r > 6) mask.data[mask.index(i, j, k)] = 1;
        if (i < 3 && j < 3) mask.data[mask.index(i, j, k)] = 1;
      }
  const auto ball = connected_component(mask, ComponentChoice::largest_interior);
  EXPECT_EQ(ball.data[ball.index(1, 1, 1)], 0);  // the block touches a face
  const auto filled = fill_holes(ball);
  double count = 0;
  for (auto x : filled.data) count += x;
  EXPECT_NEAR(count, 4.0 / 3 * M_PI * 1000, 0.03 * 4.0 / 3 * M_PI * 1000);  // the solid ball of radius 10
  // Closing bridges a one-voxel gap.
  auto gap = cube<std::uint8_t>(20);
  for (int i = 4; i < 16; ++i)
    for (int j = 8; j < 12; ++j)
      for (int k = 8; k < 12; ++k)
        if (i != 10) gap.data[gap.index(i, j, k)] = 1;
  EXPECT_EQ(close(gap, 2).data[gap.index(10, 10, 10)], 1);
  const auto seeded = connected_component(gap, ComponentChoice::containing_seed, {5, 9, 9});
  EXPECT_EQ(seeded.data[gap.index(12, 9, 9)], 0);  // the other half, across the gap
  EXPECT_THROW(connected_component(cube<std::uint8_t>(5), ComponentChoice::largest), std::runtime_error);
}

TEST(Segmentation, DiceOfKnownOverlaps) {
  auto a = cube<std::uint8_t>(10), b = cube<std::uint8_t>(10);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        a.data[a.index(i, j, k)] = i < 5;
        b.data[b.index(i, j, k)] = i < 5 ? j < 5 : 0;
      }
  EXPECT_DOUBLE_EQ(dice(a, a), 1.0);
  EXPECT_DOUBLE_EQ(dice(a, b), 2.0 * 250 / (500 + 250));
}

TEST(Segmentation, FetusFromTheSpeckledPhantomMatchesTheGroundTruth) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    PhantomSettings settings;
    settings.seed = seed;
    const Phantom p = make_phantom(settings);
    Volume<float> image;
    image.dimensions = p.image.dimensions, image.spacing_mm = p.image.spacing_mm, image.origin_mm = p.image.origin_mm;
    image.data.assign(p.image.data.begin(), p.image.data.end());
    const Mask fetus = segment_fetus(image, FetusSegmentation{});
    Mask truth = fetus;
    for (std::size_t a = 0; a < truth.data.size(); ++a) truth.data[a] = is_fetus(p.labels.data[a]);
    const double d = dice(fetus, truth);
    std::printf("seed %u: fetus Dice against the phantom's labels %.4f\n", seed, d);
    EXPECT_GE(d, 0.9) << "seed " << seed;
  }
}

}  // namespace
}  // namespace fetouch::imaging
