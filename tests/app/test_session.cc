// The lockstep session (app/session.h) against the haptics module's own lockstep simulation: with
// an analytic environment the runtime's recorded force series equals, bit for bit, what
// haptics::LockstepSession renders for the same device points (the runtime adds no timing of its
// own); two runs record the same forces; the summary agrees with the recording.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <thread>
#include <cstring>
#include <iostream>
#include <filesystem>

#include "app/realtime_cores.h"
#include "app/session.h"
#include "haptics/linear_surface_environment.h"
#include "tests/support/thread_nice.h"

namespace fetouch::app {
namespace {

namespace fs = std::filesystem;
using haptics::ContactFrame;
using testing::NiceRights;
using testing::nice_rights;

// Two contacts 3 cm apart on a flat surface, coupled (pressing one moves the other).
haptics::LinearSurfaceEnvironment two_contacts() {
  std::vector<ContactFrame> rest(2);
  rest[0].point = {0, 0, 0}, rest[1].point = {0.03, 0, 0};
  for (auto& f : rest) f.normal = Eigen::Vector3d::UnitZ(), f.curvature.setZero();
  Eigen::MatrixXd k0 = Eigen::MatrixXd::Identity(6, 6) * 400;
  k0(2, 5) = k0(5, 2) = -100;
  return haptics::LinearSurfaceEnvironment(rest, k0, 0.05 * k0);
}

// Probe 0 pokes 6 mm deep and back over 1.2 s; probe 1 presses 3 mm and holds.
std::vector<haptics::Trajectory> paths() {
  haptics::Trajectory a, b;
  a.times_s = {0, 0.1, 0.5, 0.9, 1.2};
  a.positions_m = {Eigen::Vector3d(0, 0, 0.004), Eigen::Vector3d(0, 0, 0.001), Eigen::Vector3d(0, 0, -0.006),
                   Eigen::Vector3d(0, 0, -0.006), Eigen::Vector3d(0, 0, 0.004)};
  b.times_s = {0, 0.3, 1.2};
  b.positions_m = {Eigen::Vector3d(0.03, 0, 0.002), Eigen::Vector3d(0.03, 0, -0.003), Eigen::Vector3d(0.03, 0, -0.003)};
  return {a, b};
}

SessionSettings settings(const fs::path& recording) {
  SessionSettings s;
  s.loop.local_model = haptics::LocalModelKind::pi;
  s.loop.hold = haptics::HoldKind::foh;
  s.loop.ratio = 50;
  s.probes = {"a", "b"};
  s.recording = recording;
  s.header.program_version = "test";
  return s;
}

std::vector<std::unique_ptr<haptics::Device>> replays() {
  std::vector<std::unique_ptr<haptics::Device>> devices;
  for (const auto& p : paths()) devices.push_back(std::make_unique<haptics::ReplayDevice>(p, 1e-3));
  return devices;
}

TEST(LockstepSession, ForcesEqualTheHapticsLockstepBitForBit) {
  const fs::path file = fs::temp_directory_path() / ("fetouch_session_" + std::to_string(::getpid()) + ".h5");
  auto environment = two_contacts();
  auto devices = replays();
  const SessionSettings s = settings(file);
  const SessionSummary summary = run_lockstep(environment, devices, s);
  const Recording r = read_recording(file);

  // The reference: haptics' own lockstep loop on a fresh environment, driven by the same points.
  auto reference_environment = two_contacts();
  haptics::HapticLoop loop(s.loop, haptics::initial_update(reference_environment));
  haptics::LockstepSession reference(loop, reference_environment);
  const auto a = paths()[0].resampled(1e-3), b = paths()[1].resampled(1e-3);
  ASSERT_EQ(static_cast<long>(a.size()), summary.ticks);
  ASSERT_EQ(r.devices[0].samples.size(), a.size());
  long differing = 0;
  double largest = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const auto& out = reference.tick({a[k], k < b.size() ? b[k] : b.back()});
    for (int d = 0; d < 2; ++d) {
      differing += r.devices[d].samples[k].force != out[d].force;
      largest = std::max(largest, out[d].force.norm());
    }
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(largest, 1.0);  // the poke does press
  EXPECT_EQ(summary.max_force_n, largest);
  EXPECT_EQ(summary.frames, static_cast<long>((a.size() - 1) / 50));
  EXPECT_EQ(static_cast<long>(r.frames.size()), summary.frames);
  EXPECT_GT(summary.min_stability_margin, 0);
  EXPECT_EQ(summary.newton_failures, 0);
  fs::remove(file);
}

TEST(LockstepSession, TwoRunsRecordTheSameForces) {
  std::vector<Recording> runs;
  for (int run = 0; run < 2; ++run) {
    const fs::path file = fs::temp_directory_path() / ("fetouch_session_twice_" + std::to_string(run) + ".h5");
    auto environment = two_contacts();
    auto devices = replays();
    run_lockstep(environment, devices, settings(file));
    runs.push_back(read_recording(file));
    fs::remove(file);
  }
  for (int d = 0; d < 2; ++d) {
    ASSERT_EQ(runs[0].devices[d].samples.size(), runs[1].devices[d].samples.size());
    for (std::size_t k = 0; k < runs[0].devices[d].samples.size(); ++k)
      ASSERT_EQ(std::memcmp(runs[0].devices[d].samples[k].force.data(), runs[1].devices[d].samples[k].force.data(),
                            3 * sizeof(double)),
                0)
          << "device " << d << " tick " << k;
  }
}

TEST(LockstepSession, WithoutARecordingKeepsTheSameForces) {
  // No recording file (studies keep the forces in memory): the 1201 ticks go through the sample
  // buffers more than once, and the forces kept equal the recorded run's.
  const fs::path file = fs::temp_directory_path() / ("fetouch_session_kept_" + std::to_string(::getpid()) + ".h5");
  auto recorded_environment = two_contacts();
  auto recorded_devices = replays();
  run_lockstep(recorded_environment, recorded_devices, settings(file));
  const Recording r = read_recording(file);
  fs::remove(file);
  SessionSettings s = settings(file);
  s.recording.reset();
  s.keep_forces = true;
  auto environment = two_contacts();
  auto devices = replays();
  const SessionSummary kept = run_lockstep(environment, devices, s);
  EXPECT_FALSE(fs::exists(file));
  ASSERT_EQ(kept.forces.size(), 2u);
  for (int d = 0; d < 2; ++d) {
    ASSERT_EQ(kept.forces[d].size(), r.devices[d].samples.size());
    for (std::size_t k = 0; k < kept.forces[d].size(); ++k) ASSERT_EQ(kept.forces[d][k], r.devices[d].samples[k].force) << k;
  }
}

// The real-time clock: the same session in three threads on the wall clock. Its answers can only
// differ from lockstep's in when they are taken up: every answer that is there at its frame's start
// is taken up exactly where lockstep takes it up, so the forces are equal bit for bit up to the
// first late answer (the summary names its tick; with this analytic environment, whose solve takes
// microseconds, there is normally none and the whole series must be equal). The recording holds
// every tick and every answer.
TEST(RealtimeSession, ForcesEqualLockstepUpToTheFirstLateAnswer) {
  const fs::path file = fs::temp_directory_path() / ("fetouch_session_rt_" + std::to_string(::getpid()) + ".h5");
  auto environment = two_contacts();
  auto devices = replays();
  const SessionSettings s = settings(file);
  const SessionSummary summary = run_realtime(environment, devices, s);
  const Recording r = read_recording(file);
  fs::remove(file);

  auto reference_environment = two_contacts();
  haptics::HapticLoop loop(s.loop, haptics::initial_update(reference_environment));
  haptics::LockstepSession reference(loop, reference_environment);
  const auto a = paths()[0].resampled(1e-3), b = paths()[1].resampled(1e-3);
  ASSERT_EQ(summary.ticks, static_cast<long>(a.size()));
  ASSERT_EQ(summary.timing.dropped_samples, 0);
  ASSERT_EQ(r.devices[0].samples.size(), a.size());
  ASSERT_EQ(r.devices[1].samples.size(), a.size());
  const long compared = summary.timing.first_late_tick < 0 ? static_cast<long>(a.size()) : summary.timing.first_late_tick;
  if (summary.timing.first_late_tick >= 0)
    std::cout << "[ note ] " << summary.timing.frame_overruns << " late answer(s), the first at tick "
              << summary.timing.first_late_tick << ": compared up to it\n";
  long differing = 0;
  for (long k = 0; k < compared; ++k) {
    const auto& out = reference.tick({a[k], k < static_cast<long>(b.size()) ? b[k] : b.back()});
    for (int d = 0; d < 2; ++d) differing += r.devices[d].samples[k].force != out[d].force;
    EXPECT_DOUBLE_EQ(r.devices[0].samples[k].time_s, k * 1e-3);
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(compared, 50);  // at least the first frames: their answers cannot be late by much
  // Every frame's samples were answered (none skipped: each solve takes microseconds), the last
  // frame's too, which lockstep never takes up.
  EXPECT_EQ(summary.frames, static_cast<long>((a.size() - 1) / 50) + 1 - summary.timing.skipped_frames);
  EXPECT_EQ(static_cast<long>(r.frames.size()), summary.frames);
  EXPECT_GT(summary.timing.period_p50_s, 0);
  EXPECT_GE(summary.timing.period_max_s, summary.timing.period_p99_s);
  EXPECT_GE(summary.timing.lateness_max_s, 0);
}

// The solver's thread in real time: at nice kSolverNice (-10) where the process may raise a
// thread's priority, so that other programs cannot take its core; at the nice it started with where
// it may not. What the solves' own thread had is recorded by the environment itself and compared
// with the summary; whether raising is allowed here is found by trying it on a thread of the test's.
class NiceRecordingEnvironment final : public haptics::Environment {
 public:
  explicit NiceRecordingEnvironment(haptics::Environment& inner) : inner_(inner) {}
  int contacts() const override { return inner_.contacts(); }
  void initial(haptics::EnvironmentUpdate& out) override { inner_.initial(out); }
  void solve(const std::vector<haptics::ContactSample>& samples, long frame, haptics::EnvironmentUpdate& out) override {
    nice_ = thread_nice();
    inner_.solve(samples, frame, out);
  }
  std::atomic<int> nice_{1000};

 private:
  haptics::Environment& inner_;
};

TEST(RealtimeSession, TheSolverThreadRunsAheadOfOtherProgramsWhereItMay) {
  const NiceRights rights = nice_rights(kSolverNice);
  const int started = rights.started, expected = rights.expected(kSolverNice);
  std::printf("[ note ] a thread here %s raise its nice to %d\n", rights.may ? "may" : "may not", kSolverNice);

  auto inner = two_contacts();
  NiceRecordingEnvironment environment(inner);
  auto devices = replays();
  SessionSettings s = settings(fs::path());
  s.recording.reset();
  SessionMonitor monitor;
  s.monitor = &monitor;
  const SessionSummary summary = run_realtime(environment, devices, s);
  EXPECT_GT(summary.frames, 10);
  EXPECT_EQ(environment.nice_.load(), expected);
  EXPECT_EQ(summary.timing.solver_nice, expected);
  EXPECT_EQ(monitor.solver_nice.load(), expected);
  // Asked not to raise priorities, the solver keeps the nice it started with.
  auto devices2 = replays();
  s.realtime_priority = false;
  NiceRecordingEnvironment plain(inner);
  const SessionSummary unraised = run_realtime(plain, devices2, s);
  EXPECT_EQ(plain.nice_.load(), started);
  EXPECT_EQ(unraised.timing.solver_nice, started);
}

}  // namespace
}  // namespace fetouch::app
