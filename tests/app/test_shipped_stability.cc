// Stability on the real model (issue 6): every shipped scene with each of its shipped trajectories,
// replayed by the real binary in lockstep. For every probe: no force above the scene's device
// maximum; the stability margin of the gains chosen positive at every frame; and no growing
// oscillation:
//   - no tick at the safety layer's force clamp: a loop that runs away ends there;
//   - wherever the device holds still for 300 ms or more after a change of the input (a kink of
//     the trajectory), the envelope of the force's high-pass part (the force minus its moving
//     average over one solver frame) over the hold's last 100 ms is at most half that over its
//     first 100 ms (plus 2 mN): the transient the change started decays;
//   - nowhere does the force chatter at the haptic rate: no 10 ticks in a row whose force steps
//     alternate in sign with more than 1 mN each.
// An unstable loop grows geometrically, frame by frame or tick by tick, and fails one or the other.
// (While the device moves, the frame-rate steps of the held surface are part of a ramp, not an
// oscillation, and they grow as the tissue stiffens: no decay is asked of them.)
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string scene, trajectory;  // trajectory: empty for the scene's own
  bool holds = true;              // the trajectories hold still somewhere (a slide does not)
};

// The ticks at which any probe's input changes (its velocity changes), in order, from 0 to the end.
std::vector<long> input_changes(const app::Recording& r) {
  std::set<long> changes{0};
  for (const auto& device : r.devices) {
    const auto& s = device.samples;
    for (std::size_t k = 2; k < s.size(); ++k) {
      const Eigen::Vector3d a = s[k].position - s[k - 1].position, b = s[k - 1].position - s[k - 2].position;
      if ((a - b).norm() > 1e-9) changes.insert(static_cast<long>(k - 1));
    }
    changes.insert(static_cast<long>(s.size()));
  }
  return {changes.begin(), changes.end()};
}

// Every probe still over ticks [from, to).
bool all_still(const app::Recording& r, long from, long to) {
  for (const auto& device : r.devices)
    if (device.samples[from + 1].position != device.samples[to - 1].position) return false;
  return true;
}

// The largest |high-pass force| over ticks [from, to).
double envelope(const std::vector<double>& high_pass, long from, long to) {
  double e = 0;
  for (long k = std::max(0L, from); k < std::min<long>(to, static_cast<long>(high_pass.size())); ++k)
    e = std::max(e, std::abs(high_pass[static_cast<std::size_t>(k)]));
  return e;
}

// What the oscillation checks found in one probe's force series.
struct Findings {
  double largest = 0;
  int holds = 0, holds_not_decaying = 0;
  int longest_chatter = 0;  // ticks in a row of alternating force steps over 1 mN
  long at_limit = 0;        // ticks at the safety layer's clamp (a loop that has run away)
};

Findings examine(const app::Recording& recording, const std::vector<app::DeviceSample>& s, double max_force) {
  Findings f;
  const long n = static_cast<long>(s.size());
  std::vector<double> force(s.size()), high_pass(s.size());
  for (long k = 0; k < n; ++k) {
    force[k] = s[k].force.norm(), f.largest = std::max(f.largest, force[k]);
    f.at_limit += force[k] >= max_force * (1 - 1e-9);
  }
  for (long k = 0; k < n; ++k) {  // minus the centred moving average over one frame (51 ticks)
    double sum = 0;
    int count = 0;
    for (long j = std::max(0L, k - 25); j <= std::min(n - 1, k + 25); ++j) sum += force[j], ++count;
    high_pass[k] = force[k] - sum / count;
  }
  const std::vector<long> changes = input_changes(recording);
  for (std::size_t i = 0; i + 1 < changes.size(); ++i) {
    const long from = changes[i], to = changes[i + 1];
    if (to - from < 300 || !all_still(recording, from, to)) continue;  // a hold of 300 ms or more
    ++f.holds;
    // The last window ends half a frame before the next change: the moving average reaches it.
    const double first = envelope(high_pass, from, from + 100), last = envelope(high_pass, to - 125, to - 25);
    if (last > 0.5 * first + 2e-3) {
      ++f.holds_not_decaying;
      std::printf("  hold from tick %ld to %ld: envelope %.4g N, then %.4g N\n", from, to, first, last);
    }
  }
  int run = 0;
  for (long k = 2; k < n; ++k) {
    const double a = force[k] - force[k - 1], b = force[k - 1] - force[k - 2];
    run = (a * b < 0 && std::abs(a) > 1e-3 && std::abs(b) > 1e-3) ? run + 1 : 0;
    f.longest_chatter = std::max(f.longest_chatter, run);
  }
  return f;
}

app::Recording replay(const fs::path& scene, const std::string& trajectory, const fs::path& out, YAML::Node* summary) {
  std::string command = "replay --json --mesh-every 0 --out " + out.string() + " " + scene.string();
  if (!trajectory.empty()) command += " --trajectory " + trajectory;
  const auto r = run_command(fetouch(command));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  *summary = YAML::Load(r.out);
  return app::read_recording(out / "recording.h5");
}

TEST(ShippedScenes, NoForceOscillationGrowsAndEveryFrameIsStable) {
  const fs::path source = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  std::vector<Case> cases{{"block_press.yaml", ""},          {"fetus_phantom.yaml", ""},
                          {"fetus_two_users.yaml", ""},      {"fetus_two_users_simple.yaml", ""},
                          {"fetus_simple.yaml", ""}};
  if (fs::exists(fs::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound")) {
    cases.push_back({"spine_phantom.yaml", ""});
    cases.push_back({"spine_phantom.yaml", "trajectories/spine_press_slide.csv", false});
  } else {
    std::cout << "[ skip ] the spine scene: no shared data beside the repository\n";
  }
  const fs::path dir = fs::temp_directory_path() / ("fetouch_shipped_" + std::to_string(::getpid()));
  int run = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.scene + " " + c.trajectory);
    YAML::Node summary;
    const app::Recording recording = replay(source / c.scene, c.trajectory.empty() ? "" : (source / c.trajectory).string(),
                                            dir / std::to_string(run++), &summary);
    EXPECT_EQ(summary["newton_failures"].as<long>(), 0);
    EXPECT_EQ(summary["frames_with_unstable_gains"].as<long>(), 0);
    const YAML::Node scene = YAML::LoadFile((source / c.scene).string());
    const double max_force = scene["haptics"]["max_force_n"] ? scene["haptics"]["max_force_n"].as<double>() : 3.3;
    ASSERT_FALSE(recording.frames.empty());
    double smallest_margin = 1;
    for (const auto& f : recording.frames) smallest_margin = std::min(smallest_margin, f.stability_margin);
    EXPECT_GT(smallest_margin, 0);
    for (const auto& device : recording.devices) {
      SCOPED_TRACE("probe " + device.name);
      for (const auto& sample : device.samples) ASSERT_TRUE(sample.force.allFinite());
      const Findings f = examine(recording, device.samples, max_force);
      EXPECT_LE(f.largest, max_force + 1e-12);
      EXPECT_EQ(f.at_limit, 0);  // never even at the clamp
      EXPECT_EQ(f.holds_not_decaying, 0);
      EXPECT_LT(f.longest_chatter, 10) << "the force chatters at the haptic rate";
      if (c.holds) {
        EXPECT_GE(f.holds, 1);  // the poke's or squeeze's hold at least
      }
      std::printf("%s %s probe %s: max force %.3f N (limit %.1f), smallest margin %.3f, %d holds, all decaying\n",
                  c.scene.c_str(), c.trajectory.c_str(), device.name.c_str(), f.largest, max_force, smallest_margin, f.holds);
    }
  }
  fs::remove_all(dir);
}

// The checks above can fail: the block poke with gains fixed far outside the stability region
// (the gain selection off) swings between 0 and the clamp within 100 ms of touching, then sits at
// the clamp while Newton fails under it; they say so. Only the first 1.2 s are replayed: the
// failing solves are slow.
TEST(ShippedScenes, TheOscillationChecksCatchAnUnstableLoop) {
  const fs::path source = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const fs::path dir = fs::temp_directory_path() / ("fetouch_unstable_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  ASSERT_TRUE(write_scene_variant(source / "block_press.yaml", "gains: auto",
                                  "gains: {proportional_n_per_m: 4000, integral_n_per_m: 40}", dir / "unstable.yaml"));
  YAML::Node summary;
  const fs::path shortened = dir / "poke.csv";
  {
    std::ofstream csv(shortened);
    csv << "t,x,y,z\n0,0.05,0.04,0.06\n0.5,0.05,0.04,0.05\n1.0,0.05,0.04,0.042\n1.2,0.05,0.04,0.042\n";
  }
  const app::Recording recording = replay(dir / "unstable.yaml", shortened.string(), dir / "out", &summary);
  const Findings f = examine(recording, recording.devices.at(0).samples, 3.3);
  std::printf("unstable gains: longest chatter %d ticks, %d of %d holds not decaying, %ld ticks at the 3.3 N clamp\n",
              f.longest_chatter, f.holds_not_decaying, f.holds, f.at_limit);
  EXPECT_TRUE(f.longest_chatter >= 10 || f.holds_not_decaying > 0 || f.at_limit > 0);
  // And the runtime knows: the fixed gains' robust spectral radius for each frame's stiffness.
  EXPECT_LT(summary["min_stability_margin"].as<double>(), 0);
  EXPECT_GT(summary["frames_with_unstable_gains"].as<long>(), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
