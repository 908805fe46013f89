// The shipped spine scene (issue 37): the medium the ultrasound shows, meshed around the echogenic
// spine, is what the probe presses. Its felt stiffness (the static press of 0.1 N at the squeeze's
// point, `fetouch solve`) against two independent answers: the same scene two mesh levels finer
// (every size / 2.25, same element) within 3 %, and the order of a uniform pressure of the probe's
// radius on a half-space of the medium, k = 3 pi^2 E a / (16 (1 - nu^2)) (Johnson, Contact
// Mechanics, 3.4), between half and one and a half of it. Skipped without the shared data.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

double stiffness(const fs::path& scene, const fs::path& out) {
  const auto r = run_command(fetouch("solve --json --out " + out.string() + " " + scene.string() +
                                     " --press -0.040 0.190 0.078 0 0 -0.1"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return NAN;
  const YAML::Node summary = YAML::Load(r.out);
  return 0.1 / std::abs(summary["probes"][0]["displacement_m"][2].as<double>());
}

TEST(SpineScene, TheSqueezeFeelsTheImagedMediumAndHasConverged) {
  const fs::path source = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const fs::path shared = fs::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound";
  if (!fs::exists(shared)) GTEST_SKIP() << "no shared data at " << shared.string();
  const fs::path dir = fs::temp_directory_path() / ("fetouch_spine_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // The scene names its volume relative to its folder: the variants name it absolutely.
  const std::string volume = "volume: ../../../shared/", absolute = "volume: " + (source / "../../../shared").string() + "/";
  const fs::path shipped = dir / "shipped.yaml", finer = dir / "finer.yaml";
  ASSERT_TRUE(write_scene_variant(source / "spine_phantom.yaml", volume, absolute, shipped));
  ASSERT_TRUE(write_scene_variant(shipped, "target_size_m: 0.006", "target_size_m: 0.0026667", finer));

  const YAML::Node scene = YAML::LoadFile(shipped.string());
  const double e = scene["materials"]["medium"]["youngs_modulus_pa"].as<double>();
  const double nu = scene["materials"]["medium"]["poisson_ratio"].as<double>();
  const double a = scene["probes"][0]["radius_m"].as<double>();
  const double half_space = 3 * M_PI * M_PI * e * a / (16 * (1 - nu * nu));

  const double k = stiffness(shipped, dir / "shipped"), k_fine = stiffness(finer, dir / "finer");
  std::printf("spine: felt stiffness %.2f N/m (two levels finer %.2f N/m, %.2f %%); half-space estimate %.1f N/m\n", k,
              k_fine, 100 * (k / k_fine - 1), half_space);
  EXPECT_NEAR(k, k_fine, 0.03 * k_fine);
  EXPECT_GT(k, 0.5 * half_space);
  EXPECT_LT(k, 1.5 * half_space);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
