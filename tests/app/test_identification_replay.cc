// On-line identification through the real `fetouch replay` on the default scene (fetus_phantom.yaml):
// a steady press over the fetal back (10 mm/s to 6 mm deep), held still for 2 s. From the recording:
// the stiffness identified from the device's own signals against the stiffness each frame condensed
// (the FEM's (W_n^-1)_cc), and against a third figure computed here from the recorded series alone
// (the least-squares slope of the normal force against the depth over the press's last 100 ms).
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

TEST(IdentificationReplay, SteadyPressOfTheDefaultSceneIdentifiesTheCondensedStiffness) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_identification_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const fs::path trajectory = dir / "press.csv", scene = dir / "press.yaml", out = dir / "replay";
  // Over the trunk's highest point (tests/app/test_anatomy_palpation.cc): 0.5 s to the surface,
  // 0.6 s to 6 mm deep, held 2 s, then away.
  ASSERT_EQ(run_command(fetouch("trajectory poke --at -0.014 0.006 0.0497 --normal -0.143 0.092 0.985 --approach 0.012 "
                                "--depth 0.006 --times 0.5 0.6 2.0 0.1 0.1 --out " + trajectory.string()))
                .exit_code,
            0);
  ASSERT_TRUE(write_scene_variant(scenes / "fetus_phantom.yaml", "trajectories/palpate_back.csv", trajectory.string(), scene));
  const auto r = run_command(fetouch("replay -q --json --mesh-every 0 --out " + out.string() + " " + scene.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node summary = YAML::Load(r.out);
  const std::vector<app::DeviceSample> samples = app::read_recording(out / "recording.h5").devices.at(0).samples;
  ASSERT_GT(samples.size(), 3000u);

  const Eigen::Vector3d normal = Eigen::Vector3d(-0.143, 0.092, 0.985).normalized();
  std::size_t contact = 0;
  while (contact < samples.size() && !samples[contact].in_contact) ++contact;
  ASSERT_LT(contact, samples.size());
  const double contact_s = samples[contact].time_s, press_end_s = 1.1, hold_end_s = 3.1;

  // Within 5 % of the condensed stiffness within 100 ms of contact, and at every tick from 100 ms
  // after contact to the end of the press.
  double within_s = -1, worst_press = 0;
  for (std::size_t k = contact; k < samples.size() && samples[k].time_s <= press_end_s; ++k) {
    const app::DeviceSample& s = samples[k];
    if (s.identified_stiffness_n_per_m == 0) continue;  // not identified yet
    const double error = std::abs(s.identified_stiffness_n_per_m - s.condensed_stiffness_n_per_m) / s.condensed_stiffness_n_per_m;
    if (within_s < 0 && error < 0.05) within_s = s.time_s;
    if (s.time_s >= contact_s + 0.1) worst_press = std::max(worst_press, error);
  }
  ASSERT_GE(within_s, 0);
  EXPECT_LE(within_s - contact_s, 0.1 + 1e-9);
  EXPECT_LT(worst_press, 0.05);

  // The slope of the recorded normal force against the recorded depth over the press's last 100 ms.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  const app::DeviceSample* at_press_end = nullptr;
  for (const app::DeviceSample& s : samples)
    if (s.time_s > press_end_s - 0.1 && s.time_s <= press_end_s) {
      const double depth = -normal.dot(s.position), force = normal.dot(s.force);
      sx += depth, sy += force, sxx += depth * depth, sxy += depth * force, ++n;
      at_press_end = &s;
    }
  ASSERT_NE(at_press_end, nullptr);
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  EXPECT_NEAR(at_press_end->identified_stiffness_n_per_m, slope, 0.05 * slope);

  // The 2 s hold: nothing moves, nothing drifts.
  double low = 1e300, high = 0;
  for (const app::DeviceSample& s : samples)
    if (s.time_s > press_end_s + 0.05 && s.time_s < hold_end_s - 0.05)
      low = std::min(low, s.identified_stiffness_n_per_m), high = std::max(high, s.identified_stiffness_n_per_m);
  EXPECT_LT(high - low, 0.01 * high);

  const YAML::Node id = summary["identification"]["probes"][0];
  EXPECT_GT(id["frames_compared"].as<long>(), 40);
  EXPECT_EQ(id["disagreements"].as<long>(), 0);
  std::printf("contact at %.3f s; within 5 %% of the condensed stiffness %.0f ms after; worst over the press %.2f %%; at the "
              "press's end identified %.2f N/m, condensed %.2f N/m, recorded slope %.2f N/m; hold drift %.3f %%; %ld frames "
              "compared, largest difference %.2f %%\n",
              contact_s, 1e3 * (within_s - contact_s), 100 * worst_press, at_press_end->identified_stiffness_n_per_m,
              at_press_end->condensed_stiffness_n_per_m, slope, 100 * (high - low) / high, id["frames_compared"].as<long>(),
              100 * id["max_relative_difference"].as<double>());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
