// `fetouch labels` (app/commands/labels_command.cc), the real binary on volumes written here and on
// Colin27: nested balls become nested labels of their analytic volumes, and a layer that pokes out
// of the one before it is held by it with the asked shell around it; layers on another grid, bad
// layer keys and an output over a layer are refused naming them; and the head and brain of a real
// MRI, as two labels, mesh with every interface smooth and near its label boundary (issue 37's
// acceptance on a real volume).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "imaging/volume_io.h"
#include "tests/support/run_command.h"
#include "tests/support/scratch_dir.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

// A 64^3 volume of 1 mm voxels (origin 0), 200 inside the ball of `radius` mm about `centre`, 0 out.
void write_ball(const fs::path& path, std::array<double, 3> centre, double radius, double spacing = 1.0) {
  imaging::Volume<std::uint8_t> v;
  v.dimensions = {64, 64, 64};
  v.spacing_mm = {spacing, spacing, spacing};
  v.data.assign(64 * 64 * 64, 0);
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const auto x = v.position_mm(i, j, k);
        const double r2 = std::pow(x[0] - centre[0], 2) + std::pow(x[1] - centre[1], 2) + std::pow(x[2] - centre[2], 2);
        if (r2 <= radius * radius) v.data[v.index(i, j, k)] = 200;
      }
  imaging::write_volume(v, path);
}

TEST(LabelsCommand, NestedBallsBecomeNestedLabelsAndTheOuterHoldsTheInnerWithItsShell) {
  const ScratchDir dir("fetouch_labels_balls");
  const fs::path outer = dir.path() / "outer.mha", inner = dir.path() / "inner.mha", poking = dir.path() / "poking.mha";
  write_ball(outer, {32, 32, 32}, 20);
  write_ball(inner, {32, 32, 32}, 10);
  write_ball(poking, {47, 32, 32}, 10);  // reaches 57 mm, 5 mm past the outer ball
  const double pi = std::acos(-1.0);
  {
    const fs::path out = dir.path() / "nested.mha";
    const auto r = run_command(fetouch("labels --json --out " + out.string() + " " + outer.string() + ":threshold=100 " +
                                       inner.string() + ":threshold=100"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const imaging::Volume<float> labels = imaging::read_volume(out);
    double counts[3] = {0, 0, 0};
    for (const float l : labels.data) counts[static_cast<int>(l)] += 1;
    // The balls' volumes (1 mm voxels): the inner 4/3 pi 10^3, the shell between them 4/3 pi (20^3 - 10^3).
    EXPECT_NEAR(counts[2] / (4.0 / 3 * pi * 1000), 1, 0.03);
    EXPECT_NEAR(counts[1] / (4.0 / 3 * pi * (8000 - 1000)), 1, 0.03);
    const YAML::Node j = YAML::Load(r.out);
    EXPECT_EQ(j["labels"][1]["voxels"].as<double>(), counts[2]);
  }
  {
    const fs::path out = dir.path() / "held.mha";
    const auto r = run_command(fetouch("labels --shell 3 --out " + out.string() + " " + outer.string() + ":threshold=100 " +
                                       poking.string() + ":threshold=100"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const imaging::Volume<float> labels = imaging::read_volume(out);
    const auto& n = labels.dimensions;
    const auto at = [&](int i, int j, int k) {
      return i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2] ? 0.0f : labels.data[labels.index(i, j, k)];
    };
    // The poking ball whole as label 2 (not clipped by the outer ball), and no background within 3
    // voxels of it: the outer layer was grown to hold it.
    double inside = 0;
    long bare = 0;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          if (at(i, j, k) != 2) continue;
          ++inside;
          for (int dk = -3; dk <= 3; ++dk)
            for (int dj = -3; dj <= 3; ++dj)
              for (int di = -3; di <= 3; ++di)
                if (di * di + dj * dj + dk * dk <= 9 && at(i + di, j + dj, k + dk) == 0) ++bare;
        }
    EXPECT_NEAR(inside / (4.0 / 3 * pi * 1000), 1, 0.03);
    EXPECT_EQ(bare, 0);
  }
}

TEST(LabelsCommand, LayersOnAnotherGridBadLayerKeysAndAnOutputOverALayerAreRefusedNamingThem) {
  const ScratchDir dir("fetouch_labels_refused");
  const fs::path outer = dir.path() / "outer.mha", coarse = dir.path() / "coarse.mha";
  write_ball(outer, {32, 32, 32}, 20);
  write_ball(coarse, {64, 64, 64}, 20, 2.0);
  const std::string out = " --out " + (dir.path() / "l.mha").string() + " ";
  auto r = run_command(fetouch("labels" + out + outer.string() + " " + coarse.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(coarse.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("grid of " + outer.string()), std::string::npos) << r.err;
  r = run_command(fetouch("labels" + out + outer.string() + ":close=two"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("close must be a number, not 'two'"), std::string::npos) << r.err;
  r = run_command(fetouch("labels --out " + (dir.path() / "l.txt").string() + " " + outer.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--out must end in .mha or .vti"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.path() / "l.mha"));
  const fs::path speck = dir.path() / "speck.mha";
  write_ball(speck, {32, 32, 32}, 1.5);  // 19 voxels: smoothed at 5 mm, nothing is left above one half
  r = run_command(fetouch("labels --smooth 5" + out + outer.string() + ":threshold=100 " + speck.string() + ":threshold=100"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("label 2 (" + speck.string() + ") has no voxel"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.path() / "l.mha"));
  const auto before = fs::file_size(outer);
  r = run_command(fetouch("labels --out " + outer.string() + " " + outer.string()));  // the input itself
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(outer.string()), std::string::npos) << r.err;
  EXPECT_EQ(fs::file_size(outer), before);
}

// Colin27's T1 MRI and the brain BET extracted from it (Debian's mricron-data), as head and brain:
// meshed conforming at 8 mm, every surface smooth (neighbours' normals: median <= 10, 99th
// percentile <= 35 deg), within a voxel's diagonal of its label boundary, each region's volume within
// 1 % of its voxels (counted here on the written map), smallest dihedral >= 10 deg.
TEST(LabelsCommand, Colin27HeadAndBrainMeshWithSmoothInterfacesThatFollowTheirLabels) {
  const fs::path templates = "/usr/share/mricron/templates";
  if (!fs::exists(templates / "ch2.nii.gz") || !fs::exists(templates / "ch2bet.nii.gz"))
    GTEST_SKIP() << "no Colin27 in " << templates.string() << " (Debian's mricron-data is not installed)";
  const ScratchDir dir("fetouch_labels_colin");
  const fs::path map = dir.path() / "head_brain.mha";
  const auto made = run_command(fetouch("labels --smooth 3.5 --shell 3 --out " + map.string() + " " +
                                        (templates / "ch2.nii.gz").string() + ":threshold=20:close=5 " +
                                        (templates / "ch2bet.nii.gz").string() + ":threshold=20"));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const auto meshed = run_command(fetouch("-q mesh " + map.string() + " --regions head=1 brain=2 --surface conforming "
                                          "--size 8 --json --out " + (dir.path() / "head_brain.msh").string()));
  ASSERT_EQ(meshed.exit_code, 0) << meshed.err;
  const YAML::Node j = YAML::Load(meshed.out);
  EXPECT_GE(j["quality"]["min_dihedral_deg"].as<double>(), 10);
  ASSERT_EQ(j["surfaces"].size(), 2u);  // head_outside and head_brain: the brain nowhere reaches the outside
  for (const auto& s : j["surfaces"]) {
    SCOPED_TRACE(s["name"].as<std::string>());
    EXPECT_LE(s["median_neighbour_angle_deg"].as<double>(), 10);
    EXPECT_LE(s["p99_neighbour_angle_deg"].as<double>(), 35);
    EXPECT_LE(s["max_distance_to_labels_mm"].as<double>(), std::sqrt(3.0));
  }
  const imaging::Volume<float> labels = imaging::read_volume(map);
  double voxels[3] = {0, 0, 0};
  for (const float l : labels.data) voxels[static_cast<int>(l)] += 1e-9;  // m^3 of 1 mm voxels
  ASSERT_EQ(j["regions"].size(), 2u);
  EXPECT_NEAR(j["regions"][0]["volume_m3"].as<double>() / voxels[1], 1, 0.01);
  EXPECT_NEAR(j["regions"][1]["volume_m3"].as<double>() / voxels[2], 1, 0.01);
}

}  // namespace
}  // namespace fetouch::testing
