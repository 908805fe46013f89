// `fetouch phantom` and `fetouch reconstruct`, the real binary. The phantom: MetaImage volumes that VTK reads back with the dimensions,
// spacing and label volumes the summary reports, byte-identical for the same seed, and clear
// refusals of bad options and unwritable folders.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <array>
#include <cmath>
#include <map>

#include "imaging/volume_io.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

TEST(PhantomCommand, WritesVolumesThatReadBackAsReported) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_phantom_" + std::to_string(::getpid()));
  const auto r = run_command(fetouch("phantom --json --spacing 2 --seed 5 --out " + (dir / "a").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  const auto image = imaging::read_volume(j["image"].as<std::string>());
  const auto labels = imaging::read_volume(j["label_map"].as<std::string>());
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(image.dimensions[d], j["dimensions"][d].as<int>());
    EXPECT_DOUBLE_EQ(image.spacing_mm[d], 2.0);
    EXPECT_EQ(labels.dimensions[d], image.dimensions[d]);
  }
  std::map<int, double> ml;
  for (float label : labels.data) ml[static_cast<int>(label)] += 8.0 / 1000;
  EXPECT_NEAR(ml[2], j["label_volumes_ml"]["amniotic_fluid"].as<double>(), 1e-9);
  EXPECT_NEAR(ml[1], j["label_volumes_ml"]["uterine_wall"].as<double>(), 1e-9);
  EXPECT_GT(ml[3] + ml[4] + ml[5] + ml[6], 10.0);  // a fetus of tens of millilitres
  // The same seed again: the same bytes.
  ASSERT_EQ(run_command(fetouch("phantom --spacing 2 --seed 5 --out " + (dir / "b").string())).exit_code, 0);
  EXPECT_EQ(read_file_text(dir / "a" / "phantom.mha"), read_file_text(dir / "b" / "phantom.mha"));
  EXPECT_EQ(read_file_text(dir / "a" / "phantom_labels.mha"), read_file_text(dir / "b" / "phantom_labels.mha"));
  fs::remove_all(dir);
}

// The real binary with a pose: the label map it writes has the head's centroid on the mother's right
// of the trunk's (a transverse lie, head right) and the limbs below the trunk (the back superior
// faces the fundus, +x); the summary names the pose; a pose that cannot be is refused (exit 2)
// and saying why.
TEST(PhantomCommand, APoseIsWhereTheLabelMapPutsTheFetus) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_phantom_pose_" + std::to_string(::getpid()));
  const auto r = run_command(fetouch("phantom --json --no-speckle --spacing 2 --lie transverse --back superior --head-side right --out " +
                                     dir.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_EQ(j["pose"]["lie"].as<std::string>(), "transverse");
  EXPECT_EQ(j["pose"]["presentation"].as<std::string>(), "shoulder");
  const auto labels = imaging::read_volume(j["label_map"].as<std::string>());
  std::map<int, std::array<double, 4>> sums;  // x, y, z, count per label (skull with the head)
  for (int k = 0; k < labels.dimensions[2]; ++k)
    for (int jj = 0; jj < labels.dimensions[1]; ++jj)
      for (int i = 0; i < labels.dimensions[0]; ++i) {
        int label = static_cast<int>(labels.data[labels.index(i, jj, k)]);
        if (label == 4) label = 3;
        const auto x = labels.position_mm(i, jj, k);
        for (int d = 0; d < 3; ++d) sums[label][d] += x[d];
        sums[label][3] += 1;
      }
  const auto centroid = [&](int label, int d) { return sums[label][d] / sums[label][3]; };
  EXPECT_GT(centroid(3, 1) - centroid(5, 1), 25.0);  // head 25 mm or more to the mother's right (+y)
  EXPECT_LT(std::abs(centroid(3, 0) - centroid(5, 0)), 10.0);
  EXPECT_LT(centroid(6, 0) - centroid(5, 0), -4.0);  // the limbs towards the pelvis, away from the back
  // Grown to 30 weeks: the summary gives Hadlock's measures and the volume grew with the uterus.
  const auto grown = run_command(fetouch("phantom --json --no-speckle --spacing 4 --gestational-age 30 --out " + (dir / "30w").string()));
  ASSERT_EQ(grown.exit_code, 0) << grown.err;
  const YAML::Node g = YAML::Load(grown.out);
  EXPECT_NEAR(g["gestational_age"]["hadlock_biparietal_diameter_mm"].as<double>(), 75, 3);  // about 7.5 cm at 30 weeks
  EXPECT_GT(g["dimensions"][0].as<int>(), 2 * 40);  // 160 mm at 4 mm is 40 voxels; more than twice that
  const auto bad = run_command(fetouch("phantom --lie transverse --presentation breech --out " + (dir / "bad").string()));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("presents the shoulder"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

TEST(PhantomCommand, BadOptionsAndUnwritableFoldersAreRefused) {
  const auto spacing = run_command(fetouch("phantom --spacing 0 --out /tmp/never"));
  EXPECT_EQ(spacing.exit_code, 2);
  EXPECT_NE(spacing.err.find("spacing"), std::string::npos) << spacing.err;
  const auto folder = run_command(fetouch("phantom --spacing 4 --out /proc/fetouch_cannot_write"));
  EXPECT_EQ(folder.exit_code, 1);
  EXPECT_NE(folder.err.find("/proc/fetouch_cannot_write"), std::string::npos) << folder.err;
}

}  // namespace
}  // namespace fetouch::testing

namespace fetouch::testing {
namespace {

// `fetouch reconstruct` on the shared spine sweep: the volume it writes reads back with the
// dimensions and origin it reports, which are PLUS's (147 x 106 x 104 at 0.5 mm).
TEST(ReconstructCommand, WritesTheSpineVolumeItReports) {
  const fs::path data = fs::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound";
  if (!fs::exists(data / "spine_phantom_freehand_sweep.igs.mha")) GTEST_SKIP() << "no shared data at " << data.string();
  const fs::path out = fs::temp_directory_path() / ("fetouch_spine_" + std::to_string(::getpid()) + ".mha");
  const auto r = run_command(fetouch("reconstruct --json " + (data / "spine_phantom_freehand_sweep.igs.mha").string() +
                                     " --calibration " + (data / "spine_phantom_freehand_calibration.xml").string() +
                                     " --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  const auto volume = imaging::read_volume(out);
  const int expected[3] = {147, 106, 104};
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(volume.dimensions[d], j["dimensions"][d].as<int>());
    EXPECT_EQ(volume.dimensions[d], expected[d]);
    EXPECT_NEAR(volume.origin_mm[d], j["origin_mm"][d].as<double>(), 1e-6);
  }
  fs::remove(out);
  const auto bad = run_command(fetouch("reconstruct " + (data / "spine_phantom_freehand_sweep.igs.mha").string() +
                                       " --calibration " + (data / "README.md").string()));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("PlusConfiguration"), std::string::npos) << bad.err;  // what a calibration file is
}

}  // namespace
}  // namespace fetouch::testing
