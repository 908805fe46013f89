// Two users feel each other (issue 6): `fetouch replay` on the shipped two-probe scene. User B
// presses the right side of the phantom's uterus and holds still; user A then presses the left.
//   - Through the FEM: B's force rises, by what the full solve needs to keep B's surface where B
//     holds it. Checked with `fetouch solve` (static, nonlinear, independent of the haptic loop):
//     B's baseline force alone, then A's held force with B's baseline force (B's surface is pushed
//     out by A), then A's with B's final force (B's surface is back where it was).
//   - Through the local model: with the coupling on (the Smith predictor with the condensed
//     compliance's cross terms), B's force follows A's within each frame, at the ratio the FEM's
//     steady state has; with the coupling off it stays flat within frames (moving only at the
//     solver's answers, one frame late), while the steady state is the FEM's either way.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Session {
  std::vector<app::DeviceSample> a, b;
  std::vector<Eigen::Vector3d> patches;
};

Session replay(const fs::path& scene, const fs::path& out) {
  const auto r = run_command(fetouch("replay --json --mesh-every 0 --out " + out.string() + " " + scene.string()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_EQ(j["newton_failures"].as<long>(), 0);
  EXPECT_GT(j["min_stability_margin"].as<double>(), 0);
  Session run;
  for (const auto& p : j["probes"])
    run.patches.emplace_back(p["patch_m"][0].as<double>(), p["patch_m"][1].as<double>(), p["patch_m"][2].as<double>());
  const app::Recording recording = app::read_recording(out / "recording.h5");
  run.a = recording.devices.at(0).samples;
  run.b = recording.devices.at(1).samples;
  return run;
}

// B's patch displacement along its normal (outward, +x) under two presses (force on the tissue).
double b_displacement(const fs::path& scene, const Session& run, const Eigen::Vector3d& on_a, const Eigen::Vector3d& on_b,
                      const fs::path& out) {
  std::string press;
  char text[200];
  for (int p = 0; p < 2; ++p) {
    const Eigen::Vector3d& x = run.patches[p];
    const Eigen::Vector3d& f = p == 0 ? on_a : on_b;
    std::snprintf(text, sizeof text, " --press %.17g %.17g %.17g %.17g %.17g %.17g", x.x(), x.y(), x.z(), f.x(), f.y(), f.z());
    press += text;
  }
  const auto s = run_command(fetouch("solve --json --out " + out.string() + " " + scene.string() + press));
  EXPECT_EQ(s.exit_code, 0) << s.err;
  const YAML::Node j = YAML::Load(s.out);
  return j["probes"][1]["displacement_m"][0].as<double>();
}

// The force the loop put on the tissue at a tick: the normal force along the held normal.
Eigen::Vector3d on_tissue(const app::DeviceSample& s) {
  return s.force.norm() > 0 ? Eigen::Vector3d(-s.normal_force * s.force.normalized()) : Eigen::Vector3d::Zero();
}

// Within-frame change of B's force per within-frame change of A's, summed over the frames in
// which A's force rises (N = 50).
double within_frame_ratio(const Session& r, long from, long to) {
  double db = 0, da = 0;
  for (long j = from / 50; (j + 1) * 50 <= to; ++j) {
    db += r.b[j * 50 + 49].normal_force - r.b[j * 50].normal_force;
    da += r.a[j * 50 + 49].normal_force - r.a[j * 50].normal_force;
  }
  return db / da;
}

TEST(TwoUsers, EachFeelsTheOtherAsTheFemPredicts) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_two_users_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path source = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const fs::path scene = source / "fetus_two_users.yaml";
  // The same scene with the local model's coupling off (trajectories by absolute path).
  const fs::path uncoupled_scene = dir / "uncoupled.yaml";
  ASSERT_TRUE(write_scene_variant(scene, "coupling: true", "coupling: false", uncoupled_scene));

  const Session coupled = replay(scene, dir / "coupled");
  const Session uncoupled = replay(uncoupled_scene, dir / "uncoupled");
  ASSERT_EQ(coupled.patches.size(), 2u);
  ASSERT_EQ(coupled.a.size(), 5001u);

  // Before A touches (its last tick out of contact), and at the end of A's hold (3.85 s).
  long before = 0;
  while (before + 1 < 3850 && !coupled.a[before + 1].in_contact) ++before;
  ASSERT_GT(before, 1000);  // B has pressed and held for a while by then
  const long held = 3850;
  ASSERT_TRUE(coupled.b[before].in_contact);
  ASSERT_TRUE(coupled.b[held].in_contact);
  const double rise_a = coupled.a[held].normal_force, rise_b = coupled.b[held].normal_force - coupled.b[before].normal_force;
  std::printf("A presses %.4f N; B, held still, goes from %.4f N to %.4f N (%+.4f N)\n", rise_a,
              coupled.b[before].normal_force, coupled.b[held].normal_force, rise_b);
  EXPECT_GT(rise_a, 0.5);
  EXPECT_GT(rise_b, 0.05 * rise_a);  // B feels A push the sac towards it: its force rises

  // The full FEM: B's surface under B's baseline force, then with A's press (pushed out, towards
  // B's probe), then with A's press and B's final force (back where B holds it).
  const Eigen::Vector3d a_held = on_tissue(coupled.a[held]), b_before = on_tissue(coupled.b[before]),
                        b_held = on_tissue(coupled.b[held]);
  const double d0 = b_displacement(scene, coupled, Eigen::Vector3d::Zero(), b_before, dir / "s0");
  const double d2 = b_displacement(scene, coupled, a_held, b_before, dir / "s2");
  const double d1 = b_displacement(scene, coupled, a_held, b_held, dir / "s1");
  std::printf("B's surface along +x: %.4f mm alone, %.4f mm with A's press, %.4f mm with A's press and B's new force\n",
              1e3 * d0, 1e3 * d2, 1e3 * d1);
  EXPECT_GT(d2 - d0, 2e-4);  // A's press alone pushes B's surface out by a fraction of a millimetre or more
  EXPECT_LT(std::abs(d1 - d0), 0.1 * (d2 - d0));  // B's rise is the force that holds it back

  // The local model: the frames in which A's force rises (from its first contact to 95 %).
  long rising_end = before;
  while (coupled.a[rising_end].normal_force < 0.95 * rise_a) ++rising_end;
  const double steady_ratio = rise_b / rise_a;
  const double on = within_frame_ratio(coupled, before + 50, rising_end);
  const double off = within_frame_ratio(uncoupled, before + 50, rising_end);
  std::printf("B's force per A's: steady %.4f; within frames %.4f coupled, %.4f uncoupled\n", steady_ratio, on, off);
  EXPECT_NEAR(on, steady_ratio, 0.3 * steady_ratio);
  EXPECT_LT(std::abs(off), 0.1 * steady_ratio);
  // Either way the tissue's answer is the same once A holds still: the steady forces agree.
  EXPECT_NEAR(uncoupled.b[held].normal_force, coupled.b[held].normal_force, 0.01 * coupled.b[held].normal_force);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
