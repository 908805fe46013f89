// Two users feel each other (issue 6): `fetouch replay` on the shipped two-probe scenes. User B
// presses the right side of the phantom's uterus and holds still; user A then presses the left. On
// the homogeneous tissue (fetus_two_users_simple.yaml):
//   - Through the FEM: B's force rises, by what the full solve needs to keep B's surface where B
//     holds it. Checked with `fetouch solve` (static, nonlinear, independent of the haptic loop):
//     B's baseline force alone, then A's held force with B's baseline force (B's surface is pushed
//     out by A), then A's with B's final force (B's surface is back where it was).
//   - Through the local model: with the coupling on (the Smith predictor with the condensed
//     compliance's cross terms), B's force follows A's within each frame, at the ratio the FEM's
//     steady state has; with the coupling off it stays flat within frames (moving only at the
//     solver's answers, one frame late), while the steady state is the FEM's either way.
// On the anatomy (fetus_two_users.yaml, issue 15) the amniotic fluid carries A's press to B: the
// static check as above; A's press moves B's surface more per newton than through the homogeneous
// solid, and B feels as large a share of A's force.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

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

// A's press and B's answer in a replay: A's force at the end of its hold (3.85 s) and B's rise from
// A's last tick out of contact to then.
struct Felt {
  Session run;
  long before = 0, held = 3850;
  double rise_a = 0, rise_b = 0;
};

Felt press_and_hold(const fs::path& scene, const fs::path& out) {
  Felt felt;
  felt.run = replay(scene, out);
  const Session& r = felt.run;
  EXPECT_EQ(r.patches.size(), 2u);
  EXPECT_EQ(r.a.size(), 5001u);
  if (r.a.size() != 5001u || r.b.size() != 5001u) return felt;
  while (felt.before + 1 < felt.held && !r.a[felt.before + 1].in_contact) ++felt.before;
  EXPECT_GT(felt.before, 1000);  // B has pressed and held for a while by then
  EXPECT_TRUE(r.b[felt.before].in_contact);
  EXPECT_TRUE(r.b[felt.held].in_contact);
  felt.rise_a = r.a[felt.held].normal_force;
  felt.rise_b = r.b[felt.held].normal_force - r.b[felt.before].normal_force;
  std::printf("%s: A presses %.4f N; B, held still, goes from %.4f N to %.4f N (%+.4f N, %.4f of A's)\n",
              scene.filename().c_str(), felt.rise_a, r.b[felt.before].normal_force, r.b[felt.held].normal_force,
              felt.rise_b, felt.rise_b / felt.rise_a);
  return felt;
}

// The full FEM: B's surface under B's baseline force (d0), then with A's press (d2: pushed out,
// towards B's probe), then with A's press and B's final force (d1: back where B holds it).
struct Static {
  double d0 = 0, d1 = 0, d2 = 0;
};

Static static_solves(const fs::path& scene, const Felt& felt, const fs::path& dir) {
  const Session& r = felt.run;
  const Eigen::Vector3d a_held = on_tissue(r.a[felt.held]), b_before = on_tissue(r.b[felt.before]),
                        b_held = on_tissue(r.b[felt.held]);
  Static s;
  s.d0 = b_displacement(scene, r, Eigen::Vector3d::Zero(), b_before, dir / "s0");
  s.d2 = b_displacement(scene, r, a_held, b_before, dir / "s2");
  s.d1 = b_displacement(scene, r, a_held, b_held, dir / "s1");
  std::printf("B's surface along +x: %.4f mm alone, %.4f mm with A's press, %.4f mm with A's press and B's new force\n",
              1e3 * s.d0, 1e3 * s.d2, 1e3 * s.d1);
  return s;
}

fs::path fresh_directory(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

const fs::path kScenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";

TEST(TwoUsers, EachFeelsTheOtherAsTheFemPredicts) {
  const fs::path dir = fresh_directory("fetouch_two_users");
  const fs::path scene = kScenes / "fetus_two_users_simple.yaml";
  // The same scene with the local model's coupling off (trajectories by absolute path).
  const fs::path uncoupled_scene = dir / "uncoupled.yaml";
  ASSERT_TRUE(write_scene_variant(scene, "coupling: true", "coupling: false", uncoupled_scene));

  const Felt felt = press_and_hold(scene, dir / "coupled");
  const Session& coupled = felt.run;
  const Session uncoupled = replay(uncoupled_scene, dir / "uncoupled");
  ASSERT_EQ(coupled.a.size(), 5001u);
  ASSERT_EQ(uncoupled.b.size(), 5001u);
  const double rise_a = felt.rise_a, rise_b = felt.rise_b;
  EXPECT_GT(rise_a, 0.5);
  EXPECT_GT(rise_b, 0.05 * rise_a);  // B feels A push the sac towards it: its force rises

  const Static s = static_solves(scene, felt, dir);
  EXPECT_GT(s.d2 - s.d0, 2e-4);  // A's press alone pushes B's surface out by a fraction of a millimetre or more
  EXPECT_LT(std::abs(s.d1 - s.d0), 0.1 * (s.d2 - s.d0));  // B's rise is the force that holds it back

  // The local model: the frames in which A's force rises (from its first contact to 95 %).
  long rising_end = felt.before;
  while (coupled.a[rising_end].normal_force < 0.95 * rise_a) ++rising_end;
  const double steady_ratio = rise_b / rise_a;
  const double on = within_frame_ratio(coupled, felt.before + 50, rising_end);
  const double off = within_frame_ratio(uncoupled, felt.before + 50, rising_end);
  std::printf("B's force per A's: steady %.4f; within frames %.4f coupled, %.4f uncoupled\n", steady_ratio, on, off);
  EXPECT_NEAR(on, steady_ratio, 0.3 * steady_ratio);
  EXPECT_LT(std::abs(off), 0.1 * steady_ratio);
  // Either way the tissue's answer is the same once A holds still: the steady forces agree.
  EXPECT_NEAR(uncoupled.b[felt.held].normal_force, coupled.b[felt.held].normal_force,
              0.01 * coupled.b[felt.held].normal_force);
  fs::remove_all(dir);
}

// The same presses on the anatomy (issue 15): the amniotic fluid keeps its volume, so A's press
// raises the sac's pressure and pushes the wall out under B. B's force rises as a static solve of
// the same scene says it must, and by more of A's force than in the homogeneous tissue: the fluid
// carries the press across.
TEST(TwoUsers, TheFluidCarriesOnePressToTheOtherUser) {
  const fs::path dir = fresh_directory("fetouch_two_users_fluid");
  const fs::path scene = kScenes / "fetus_two_users.yaml";
  const Felt fluid = press_and_hold(scene, dir / "anatomy");
  const Felt solid = press_and_hold(kScenes / "fetus_two_users_simple.yaml", dir / "homogeneous");
  ASSERT_EQ(fluid.run.a.size(), 5001u);
  ASSERT_EQ(solid.run.a.size(), 5001u);
  EXPECT_GT(fluid.rise_a, 0.05);
  EXPECT_GT(fluid.rise_b, 0);  // B feels A: its force rises

  const Static s = static_solves(scene, fluid, dir);
  EXPECT_GT(s.d2 - s.d0, 2e-4);                           // A's press alone pushes B's surface out
  EXPECT_LT(std::abs(s.d1 - s.d0), 0.1 * (s.d2 - s.d0));  // B's rise is the force that holds it back
  // The coupling: how far A's press moves B's surface per newton (the cross compliance, static),
  // and the share of A's force that B feels rise (replayed).
  const Static h = static_solves(kScenes / "fetus_two_users_simple.yaml", solid, dir / "homogeneous_static");
  const double moved_fluid = (s.d2 - s.d0) / fluid.rise_a, moved_solid = (h.d2 - h.d0) / solid.rise_a;
  const double through_fluid = fluid.rise_b / fluid.rise_a, through_solid = solid.rise_b / solid.rise_a;
  std::printf("A's press moves B's surface %.2f mm/N through the fluid, %.2f mm/N through the homogeneous solid\n",
              1e3 * moved_fluid, 1e3 * moved_solid);
  std::printf("B's rise per A's force: %.4f through the fluid, %.4f through the homogeneous solid\n", through_fluid,
              through_solid);
  EXPECT_GT(moved_fluid, 2 * moved_solid);
  // The share B feels is the cross compliance over B's own, and both grow with a softer tissue: the
  // fluid keeps it (not less than nine tenths of the solid's).
  EXPECT_GT(through_fluid, 0.9 * through_solid);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
