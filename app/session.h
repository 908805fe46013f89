// A haptic session in simulated time (lockstep, ARCHITECTURE.md section 5): devices move, the
// 1 kHz loop renders, the environment answers each frame one frame later, and everything is
// recorded (app/recording.h). Bit-for-bit reproducible: the same scene, devices and environment give
// the same bytes. The runtime adds no timing of its own: with an analytic environment its forces are
// exactly those of haptics::LockstepSession driven by the same device points.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/recording.h"
#include "haptics/devices.h"
#include "haptics/environment.h"
#include "haptics/haptic_loop.h"

namespace fetouch::app {

struct SessionSettings {
  haptics::HapticLoopSettings loop;
  std::vector<std::string> probes;          // one per device, in order
  std::optional<std::filesystem::path> recording;  // the HDF5 file, if any
  RecordingHeader header;                   // probes, rate and ratio are filled in here
  double flush_period_s = 0.5;              // wall-clock time between flushes of the recording
  long max_ticks = -1;                      // < 0: until every device has finished
  // Called after each frame's update is taken up (outside the tick): frame number, time.
  std::function<void(long, double)> after_frame;
  bool keep_forces = false;                 // the summary keeps every force sent (studies)
};

struct SessionSummary {
  long ticks = 0, frames = 0;
  double solve_p50_s = 0, solve_p99_s = 0, solve_max_s = 0;  // the environment's solve times
  long newton_failures = 0;
  double max_force_n = 0;            // the largest force sent to a device
  double min_stability_margin = 1;   // 1 - spectral radius of the chosen gains, over the frames
  long frames_with_unstable_gains = 0;
  std::vector<std::vector<Eigen::Vector3d>> forces;  // per device, per tick (keep_forces)
};

// Runs until the devices finish (or max_ticks). Allocation happens only outside the tick.
SessionSummary run_lockstep(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings);

}  // namespace fetouch::app
