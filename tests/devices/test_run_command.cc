// `fetouch run` and `fetouch devices` with the stand-in libHD.so: the real binary, the real session on
// the stand-in's servo thread, the shipped default scene with its probe on a PHANTOM.
//   - the forces the stand-in received are the forces the session recorded, tick for tick, each
//     finite and within the clamp (the stand-in's own count of violations is zero);
//   - with the stand-in's hand the virtual operator's and its target the scene's trajectory, the
//     forces agree with a lockstep `replay` using the `operator` device: both are the same hand
//     model, loop and tissue, and differ only in when each frame's answer arrives (in real time a
//     solve is applied at the first frame start after it is ready, in lockstep exactly one frame
//     later; ReplayCommand.RealTimeRendersTheLockstepForces bounds that by 1 % of the peak force), in
//     when a background factorisation is taken up (in real time, when it is not ready at the frame
//     lockstep waits for it, at the first frame after) and in the engage ramp (0.5 s, over while
//     the probe is still in the air);
//   - each injected fault ends as docs/devices.md says: a message naming the cause, exit 1, no force
//     above the clamp, the recording readable up to the fault;
//   - without a libHD.so, `devices` and `run` say why in one line.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
const std::string kReplayDevice = "type: replay\n      trajectory: trajectories/poke_fetus.csv";

struct Standin {
  std::vector<Eigen::Vector3d> forces;
  long violations = -1;
};

// The forces the stand-in's device `device` (all, when empty) was sent, in order.
Standin read_standin_log(const fs::path& path, const std::string& device = "") {
  Standin s;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# violations ", 0) == 0) s.violations = std::stol(line.substr(13));
    char name[64];
    double t, f[3], x[3];
    if (std::sscanf(line.c_str(), "%63[^,],%lf,%lf,%lf,%lf,%lf,%lf,%lf", name, &t, &f[0], &f[1], &f[2], &x[0], &x[1], &x[2]) == 8 &&
        (device.empty() || device == name))
      s.forces.emplace_back(f[0], f[1], f[2]);
  }
  return s;
}

class RunCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("fetouch_run_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_TRUE(write_scene_variant(kScenes / "fetus_simple.yaml", kReplayDevice, "type: phantom", dir_ / "phantom.yaml"));
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The stand-in's environment: its hand pulled along the scene's trajectory, its log in the folder.
  std::string standin(const std::string& fault = "", const std::string& extra = "") const {
    return "FETOUCH_LIBHD=" + std::string(STANDIN_LIBHD) + " FETOUCH_STANDIN_TRAJECTORY=" +
           (kScenes / "trajectories" / "poke_fetus.csv").string() + " FETOUCH_STANDIN_LOG=" + (dir_ / "standin.csv").string() +
           (fault.empty() ? "" : " FETOUCH_STANDIN_FAULT=" + fault) + " " + extra + " ";
  }

  fs::path dir_;
};

TEST_F(RunCommand, TheStandinReceivesExactlyTheRecordedForcesAndAgreesWithTheOperatorReplay) {
  const auto r = run_command(standin() + fetouch("-q run --json --duration 3.5 --out " + (dir_ / "run").string() + " " +
                                                 (dir_ / "phantom.yaml").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_EQ(j["fault"].as<std::string>(), "");
  EXPECT_EQ(j["ticks"].as<long>(), 3500);
  const app::Recording recording = app::read_recording(dir_ / "run" / "recording.h5");
  const auto& ticks = recording.devices.at(0).samples;
  const Standin sent = read_standin_log(dir_ / "standin.csv");
  EXPECT_EQ(sent.violations, 0);
  // One frame more than the ticks: the query of where the device is before the session (no force).
  ASSERT_EQ(sent.forces.size(), ticks.size() + 1);
  EXPECT_EQ(sent.forces[0].norm(), 0);
  double peak = 0;
  for (std::size_t k = 0; k < ticks.size(); ++k) {
    ASSERT_TRUE(sent.forces[k + 1].allFinite()) << k;
    EXPECT_LE(sent.forces[k + 1].norm(), 3.3 + 1e-9) << k;
    EXPECT_NEAR((sent.forces[k + 1] - ticks[k].force).norm(), 0, 1e-12) << k;  // identity mapping: N in, N out
    peak = std::max(peak, ticks[k].force.norm());
  }
  EXPECT_GT(peak, 0.2);  // the probe pressed the tissue

  // The same scene with the virtual operator in lockstep.
  ASSERT_TRUE(write_scene_variant(kScenes / "fetus_simple.yaml", kReplayDevice,
                                  "type: operator\n      trajectory: trajectories/poke_fetus.csv", dir_ / "operator.yaml"));
  const auto l = run_command(fetouch("-q replay --mesh-every 0 --out " + (dir_ / "lockstep").string() + " " +
                                     (dir_ / "operator.yaml").string()));
  ASSERT_EQ(l.exit_code, 0) << l.err;
  const app::Recording replayed = app::read_recording(dir_ / "lockstep" / "recording.h5");
  const auto& lockstep = replayed.devices.at(0).samples;
  const std::size_t n = std::min(lockstep.size(), ticks.size());
  ASSERT_GT(n, 3000u);
  // Up to the first frame whose answer came late (the summary's first_late_tick; -1: none), and to
  // the first one solved without the factorisation lockstep uses (first_solver_difference_tick), the
  // real-time forces are lockstep's; after them they differ by what the late answers held back and
  // by the solves' tolerance, which depends on how busy the machine is, so only their RMS is bounded.
  const long late_answer = j["first_late_tick"].as<long>(), solver_difference = j["first_solver_difference_tick"].as<long>();
  const long first_late = late_answer < 0 ? solver_difference : solver_difference < 0 ? late_answer : std::min(late_answer, solver_difference);
  double squared = 0, worst = 0, worst_on_time = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double e = (lockstep[k].force - ticks[k].force).norm();
    squared += e * e, worst = std::max(worst, e);
    if (first_late < 0 || static_cast<long>(k) < first_late) worst_on_time = std::max(worst_on_time, e);
  }
  const double rms = std::sqrt(squared / double(n));
  std::printf("run on the stand-in against lockstep replay with the operator: RMS %.4f N, worst %.4f N (%.2g N before the "
              "first late answer, tick %ld, or solver difference, tick %ld), peak %.3f N\n",
              rms, worst, worst_on_time, late_answer, solver_difference, peak);
  EXPECT_LT(rms, 0.01 * peak);
  EXPECT_LT(worst_on_time, 1e-9 * peak);
}

TEST_F(RunCommand, TwoUsersOnTwoDevicesByName) {
  std::string text = read_file_text(kScenes / "fetus_two_users_simple.yaml");
  for (const char* user : {"a", "b"}) {
    const std::string from = "type: replay\n      trajectory: trajectories/two_users_" + std::string(user) + ".csv";
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos);
    text.replace(at, from.size(), "type: phantom\n      name: user_" + std::string(user));
  }
  // PHANTOMs have no path known beforehand to refine the mesh around: 8 mm throughout.
  const std::string refine = ", refine: {around_probes: true, size_m: 0.004}";
  ASSERT_NE(text.find(refine), std::string::npos);
  text.erase(text.find(refine), refine.size());
  std::ofstream(dir_ / "two.yaml") << text;
  const fs::path t = kScenes / "trajectories";
  const auto r = run_command("FETOUCH_LIBHD=" + std::string(STANDIN_LIBHD) + " FETOUCH_STANDIN_DEVICES=user_a,user_b" +
                             " FETOUCH_STANDIN_TRAJECTORY=user_a=" + (t / "two_users_a.csv").string() + ",user_b=" +
                             (t / "two_users_b.csv").string() + " FETOUCH_STANDIN_LOG=" + (dir_ / "standin.csv").string() + " " +
                             fetouch("-q run --json --duration 4 --out " + (dir_ / "run").string() + " " + (dir_ / "two.yaml").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const app::Recording recording = app::read_recording(dir_ / "run" / "recording.h5");
  for (int d = 0; d < 2; ++d) {
    const auto& ticks = recording.devices.at(d).samples;
    const Standin sent = read_standin_log(dir_ / "standin.csv", d == 0 ? "user_a" : "user_b");
    EXPECT_EQ(sent.violations, 0);
    ASSERT_EQ(sent.forces.size(), ticks.size() + 1) << d;  // + the position query before the session
    double peak = 0;
    for (std::size_t k = 0; k < ticks.size(); ++k) {
      EXPECT_NEAR((sent.forces[k + 1] - ticks[k].force).norm(), 0, 1e-12) << d << " " << k;
      peak = std::max(peak, ticks[k].force.norm());
    }
    EXPECT_GT(peak, 0.1) << d;  // each user pressed
  }
}

TEST_F(RunCommand, SigtermRampsTheForceOutAndWritesEverything) {
  // The probe presses from about 1 s; a session meant to last 60 s.
  const std::string run = standin() + fetouch("-q run --json --duration 60 --out " + (dir_ / "run").string() + " " +
                                              (dir_ / "phantom.yaml").string());
  // SIGTERM 2.5 s after the session has started (its partial recording exists).
  const std::string partial = (dir_ / "run" / "recording.partial.h5").string();
  const auto r = run_command("sh -c '" + run + " & p=$!; while [ ! -e " + partial +
                             " ] && kill -0 $p 2>/dev/null; do sleep 0.1; done; sleep 2.5; kill -TERM $p; wait $p'");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_TRUE(j["stopped"].as<bool>());
  EXPECT_LT(j["ticks"].as<long>(), 10000);
  EXPECT_TRUE(fs::exists(dir_ / "run" / "summary.json"));
  const app::Recording recording = app::read_recording(dir_ / "run" / "recording.h5");
  const auto& ticks = recording.devices.at(0).samples;
  ASSERT_GT(ticks.size(), 400u);
  // The last 0.2 s: the force scaled down linearly to zero (the scale is (n - i) / n of the tick's force).
  EXPECT_EQ(ticks.back().force.norm(), 0);
  for (std::size_t i = 1; i <= 50; ++i) EXPECT_LE(ticks[ticks.size() - i].force.norm(), 3.3 * double(i) / 200 + 1e-12) << i;
  EXPECT_EQ(read_standin_log(dir_ / "standin.csv").violations, 0);
}

TEST_F(RunCommand, ADeviceFaultEndsTheSessionWithTheRecordingIntact) {
  const auto r = run_command(standin("device_fault", "FETOUCH_STANDIN_FAULT_AT=1.2") +
                             fetouch("-q run --duration 3 --out " + (dir_ / "run").string() + " " + (dir_ / "phantom.yaml").string()));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("HD_DEVICE_FAULT (0x300"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("probe tool"), std::string::npos) << r.err;
  const app::Recording recording = app::read_recording(dir_ / "run" / "recording.h5");
  const auto& ticks = recording.devices.at(0).samples;
  ASSERT_FALSE(ticks.empty());
  // Up to the fault and the 0.2 s over which the session ramps the other devices' forces out.
  EXPECT_NEAR(ticks.back().time_s, 1.4, 0.05);
  for (const auto& tick : ticks)
    if (tick.time_s > 1.203) {
      EXPECT_EQ(tick.force.norm(), 0) << tick.time_s;  // what the faulted device was sent
    }
  const Standin sent = read_standin_log(dir_ / "standin.csv");
  EXPECT_EQ(sent.violations, 0);
  for (std::size_t k = 1203; k < sent.forces.size(); ++k) {  // the query's frame, then the ticks
    EXPECT_EQ(sent.forces[k].norm(), 0) << k;
  }
}

TEST_F(RunCommand, ForceErrorsAreCountedAndTheSessionGoesOn) {
  const auto r = run_command(standin("force_burst", "FETOUCH_STANDIN_FAULT_AT=1.2") +
                             fetouch("-q run --json --duration 2 --out " + (dir_ / "run").string() + " " + (dir_ / "phantom.yaml").string()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("force errors"), std::string::npos) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_GE(j["recoverable_errors"][0].as<long>(), 45);
  EXPECT_EQ(j["ticks"].as<long>(), 2000);
  EXPECT_EQ(read_standin_log(dir_ / "standin.csv").violations, 0);
}

TEST_F(RunCommand, AServoStallIsSeenInTheTickFigures) {
  const auto r = run_command(standin("stall", "FETOUCH_STANDIN_FAULT_AT=1.0") +
                             fetouch("-q run --json --duration 2 --out " + (dir_ / "run").string() + " " + (dir_ / "phantom.yaml").string()));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_GE(j["tick_period_max_s"].as<double>(), 0.29);  // the stand-in stalled its servo thread 300 ms
  EXPECT_GE(j["late_ticks"].as<long>(), 1);
}

TEST_F(RunCommand, FaultsAtStartAreNamedInOneLine) {
  for (const auto& [fault, expected] : {std::pair<std::string, std::string>{"init", "HD_COMM_ERROR"}, {"uncalibrated", "not calibrated"}}) {
    const auto r = run_command(standin(fault) + fetouch("run --duration 1 --out " + (dir_ / "run").string() + " " +
                                                        (dir_ / "phantom.yaml").string()));
    EXPECT_EQ(r.exit_code, 1) << fault;
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  for (const std::string& library : {std::string("/nonexistent/libHD.so"), std::string(STANDIN_BROKEN_LIBHD)}) {
    const auto r = run_command("FETOUCH_LIBHD=" + library + " " +
                               fetouch("run --duration 1 --out " + (dir_ / "run").string() + " " + (dir_ / "phantom.yaml").string()));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(library), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    const auto d = run_command("FETOUCH_LIBHD=" + library + " " + fetouch("devices"));
    EXPECT_EQ(d.exit_code, 1);
    EXPECT_NE(d.err.find(library), std::string::npos) << d.err;
    EXPECT_EQ(std::count(d.err.begin(), d.err.end(), '\n'), 1) << d.err;
  }
}

TEST_F(RunCommand, DevicesDescribesTheStandin) {
  const auto r = run_command("FETOUCH_LIBHD=" + std::string(STANDIN_LIBHD) + " " + fetouch("devices --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  ASSERT_EQ(j["devices"].size(), 1u);
  EXPECT_EQ(j["devices"][0]["serial"].as<std::string>(), "STANDIN-0001");
  EXPECT_EQ(j["devices"][0]["update_rate_hz"].as<double>(), 1000);
  EXPECT_EQ(j["devices"][0]["calibration"].as<std::string>(), "ok");
  EXPECT_EQ(j["devices"][0]["max_continuous_force_n"].as<double>(), 3.3);
}

// `fetouch devices --timing`: the real binary runs the haptic thread's schedule and reports it; no
// libHD.so is needed for that.
TEST_F(RunCommand, DevicesTimingReportsTheHapticSchedule) {
  const auto r = run_command("FETOUCH_LIBHD=/nonexistent/libHD.so " + fetouch("devices --timing 0.25 --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_EQ(j["ticks"].as<long>(), 250);
  EXPECT_EQ(j["period_s"].as<double>(), 1e-3);
  const long late = j["later_than_1ms"].as<long>(), somewhat = j["later_than_100us"].as<long>();
  EXPECT_LE(late, somewhat);
  EXPECT_LE(somewhat, 250);
  EXPECT_LE(j["lateness_p99_s"].as<double>(), j["lateness_max_s"].as<double>());
  EXPECT_EQ(late > 0, j["lateness_max_s"].as<double>() > 1e-3);
  const auto bad = run_command(fetouch("devices --timing 0"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--timing"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace fetouch::testing
