// The passivity layer through the real `fetouch replay`, on the shipped hard case: a stiff block
// (1 MPa) under a light, stiff, barely damped grip (stiff_block_grip.yaml). With the layer only
// observing, the force the device is sent rings between zero and the clamp through the hold (what
// the issue reported) and the port's energy shows the loop generating; with the shipped default
// (the layer on) the hold is still and the energy the loop handed the hand stays within a few
// allowances. The summary's figures are checked against the recording's own series.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

// The scene with its trajectory made absolute and `extra` added to its haptics section.
fs::path scene_copy(const fs::path& dir, const std::string& name, const std::string& extra) {
  const fs::path shipped = fs::path(FETOUCH_SOURCE_DIR) / "config/scenes/stiff_block_grip.yaml";
  std::ifstream in(shipped);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string trajectory = "trajectories/poke_block.csv";
  s.replace(s.find(trajectory), trajectory.size(), (shipped.parent_path() / trajectory).string());
  const std::string clamp = "  max_force_n: 8.5\n";
  s.replace(s.find(clamp), clamp.size(), clamp + extra);
  fs::create_directories(dir);
  const fs::path out = dir / (name + ".yaml");
  std::ofstream(out) << s;
  return out;
}

struct Replayed {
  YAML::Node summary;
  std::vector<app::DeviceSample> samples;
  std::vector<app::FrameRecord> frames;
};

Replayed replay(const fs::path& dir, const fs::path& scene) {
  const fs::path out = dir / scene.stem();
  const auto r = run_command(fetouch("replay -q --json --out " + out.string() + " " + scene.string()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  Replayed run;
  run.summary = YAML::Load(r.out);
  const app::Recording recording = app::read_recording(out / "recording.h5");
  run.samples = recording.devices.at(0).samples;
  run.frames = recording.frames;
  return run;
}

// Peak to peak of the force's magnitude over [from, to] s, and the lowest port energy recorded.
double swing(const std::vector<app::DeviceSample>& samples, double from, double to) {
  double low = 1e300, high = -1e300;
  for (const auto& s : samples)
    if (s.time_s >= from && s.time_s <= to) low = std::min(low, s.force.norm()), high = std::max(high, s.force.norm());
  return high - low;
}

TEST(PassivityReplay, StiffBlockUnderALightGripRingsWithoutTheLayerAndIsStillWithIt) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_passivity_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const Replayed observed = replay(dir, scene_copy(dir, "observe", "  passivity: {mode: observe}\n"));
  const Replayed shipped = replay(dir, scene_copy(dir, "default", ""));
  ASSERT_EQ(observed.samples.size(), 3001u);
  ASSERT_EQ(shipped.samples.size(), 3001u);

  // The poke holds its depth from 1.0 s to 2.0 s; the last 0.7 s of it must be still.
  const double clamp = 8.5;
  EXPECT_GT(swing(observed.samples, 1.3, 2.0), 0.9 * clamp) << "the hard case must ring at the clamp unprotected";
  EXPECT_LT(swing(shipped.samples, 1.3, 2.0), 0.05);
  for (const auto& s : shipped.samples) ASSERT_TRUE(s.force.allFinite() && s.force.norm() <= clamp + 1e-12);

  // The summary reads what the recording holds.
  const auto lowest = [](const std::vector<app::DeviceSample>& samples) {
    double e = 0;
    for (const auto& s : samples) e = std::min(e, s.port_energy_j);
    return e;
  };
  const YAML::Node off = observed.summary["passivity"], on = shipped.summary["passivity"];
  EXPECT_EQ(off["mode"].as<std::string>(), "observe");
  EXPECT_EQ(on["mode"].as<std::string>(), "on");
  EXPECT_NEAR(off["probes"][0]["min_port_energy_j"].as<double>(), lowest(observed.samples), 1e-9);
  EXPECT_NEAR(on["probes"][0]["min_port_energy_j"].as<double>(), lowest(shipped.samples), 1e-9);
  EXPECT_LT(lowest(observed.samples), -1.0) << "ringing at 8.5 N hands the hand joules";
  EXPECT_GT(lowest(shipped.samples), -25 * 2e-5) << "the layer lets a contact lend a few allowances at most";
  EXPECT_EQ(off["probes"][0]["controller_ticks"].as<long>(), 0);
  EXPECT_GT(on["probes"][0]["controller_ticks"].as<long>(), 0);
  double lowest_scale = 1;
  for (const auto& s : shipped.samples) lowest_scale = std::min(lowest_scale, s.passivity_scale);
  EXPECT_NEAR(on["probes"][0]["min_scale"].as<double>(), lowest_scale, 1e-12);

  // The controller's force per tick: none while observing; with the layer on, its largest is the
  // summary's, and on every tick the safety layer let through untouched it is what the scaling
  // took away, min(F_c, clamp) n - f (n along the force sent, F_c the local model's request).
  double largest = 0;
  long checked = 0, agree = 0;
  for (const auto& s : observed.samples) ASSERT_EQ(s.controller_force.norm(), 0.0);
  for (const auto& s : shipped.samples) {
    largest = std::max(largest, s.controller_force.norm());
    if (s.force.norm() < 1e-9 || s.normal_force <= 0) continue;
    const Eigen::Vector3d expected = std::min(s.normal_force, clamp) * s.force.normalized() - s.force;
    ++checked;
    agree += (s.controller_force - expected).norm() < 1e-9;
  }
  EXPECT_NEAR(on["probes"][0]["max_controller_force_n"].as<double>(), largest, 1e-12);
  EXPECT_GT(largest, 0.5);
  EXPECT_GT(checked, 1000);
  EXPECT_GT(agree, 0.9 * checked) << agree << " of " << checked;

  // The frame-rate energy audit: the hand's energy over the audited frames is the port observer's
  // at the tick that closed the last of them; the frames that generated (over 1 uJ) are the
  // summary's; unprotected, most frames of the ringing hold generate, with the layer few do.
  for (const Replayed* run : {&observed, &shipped}) {
    double hand = 0;
    long generating = 0, last = -1;
    for (const app::FrameRecord& f : run->frames) {
      ASSERT_EQ(f.hand_energy_j.size(), 1u);
      hand += f.hand_energy_j[0];
      generating += f.generated_energy_j[0] > 1e-6;
      last = f.energy_frame;
    }
    ASSERT_GT(last, 0);
    const double observer = run->samples.at(static_cast<std::size_t>(50 * (last + 1))).port_energy_j;
    EXPECT_NEAR(hand, observer, 1e-9 + 1e-9 * std::abs(observer));
    EXPECT_EQ(run->summary["passivity"]["probes"][0]["generating_frames"].as<long>(), generating);
  }
  const long unprotected = off["probes"][0]["generating_frames"].as<long>(), protected_ = on["probes"][0]["generating_frames"].as<long>();
  EXPECT_GE(unprotected, 30);  // of 60
  EXPECT_LE(5 * protected_, unprotected);
  fs::remove_all(dir);
}

// The stylus hand (Fu & Cavusoglu's two stages, scene key hand: {model: stylus}) through the real
// binary: block_press poked by it and held 1 s at 8 mm. Once still, the handle sits above the
// target by the force over the two stages in series, F (1/k1 + 1/k2) with the stylus defaults
// (575 and 175 N/m: 7.45 mm per newton), not F / k of the one-mass hand (300 N/m: 3.33 mm per N).
TEST(PassivityReplay, AStylusHandHoldsAboveItsTargetByTheForceOverItsStagesInSeries) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_stylus_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path shipped = fs::path(FETOUCH_SOURCE_DIR) / "config/scenes/block_press.yaml";
  std::ifstream in(shipped);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string device = "      type: replay\n      trajectory: trajectories/poke_block.csv\n";
  ASSERT_NE(s.find(device), std::string::npos);
  s.replace(s.find(device), device.size(),
            "      type: operator\n      trajectory: " + (shipped.parent_path() / "trajectories/poke_block.csv").string() +
                "\n      hand: {model: stylus}\n");
  const fs::path scene = dir / "stylus.yaml";
  std::ofstream(scene) << s;
  const Replayed run = replay(dir, scene);
  ASSERT_EQ(run.samples.size(), 3001u);

  // The poke's target holds z = 0.042 m from 1.0 s to 2.0 s; the last 0.2 s of it.
  double force = 0, gap = 0, low = 1e300, high = -1e300;
  int n = 0;
  for (const auto& sample : run.samples)
    if (sample.time_s >= 1.8 && sample.time_s <= 2.0) {
      force += sample.force.z(), gap += sample.position.z() - 0.042, ++n;
      low = std::min(low, sample.force.z()), high = std::max(high, sample.force.z());
    }
  force /= n, gap /= n;
  ASSERT_GT(force, 0.05) << "the stylus must press the block";
  EXPECT_LT(high - low, 0.01 * force) << "still";
  EXPECT_NEAR(gap, force * (1 / 575.0 + 1 / 175.0), 0.02 * gap);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
