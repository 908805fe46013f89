#include "app/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <thread>

#include "app/progress.h"
#include "app/session_base.h"
#include "app/session_rows.h"

namespace fetouch::app {

using detail::SessionBase;

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(p * double(values.size())));
  return values[std::min(rank == 0 ? 0 : rank - 1, values.size() - 1)];
}

SessionSummary run_lockstep(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings) {
  SessionBase base(environment, devices, settings);
  haptics::HapticLoop loop(settings.loop, haptics::initial_update(environment));
  haptics::LockstepSession session(loop, environment);
  const int m = base.devices();
  const long ticks = base.ticks();
  const double period = settings.loop.period_s;
  std::optional<Progress> progress;  // frames done, on standard error
  std::string first_failure;
  if (settings.progress) progress.emplace("frames", ticks / settings.loop.ratio, std::cerr, Progress::stderr_is_terminal());

  // Buffers sized once: the tick loop below only fills them.
  const std::size_t batch = 1000;
  std::vector<std::vector<DeviceSample>> pending(static_cast<std::size_t>(m), std::vector<DeviceSample>(batch));
  std::size_t filled = 0;
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(m)), last_points(static_cast<std::size_t>(m));
  std::vector<Eigen::Vector3d> velocities(static_cast<std::size_t>(m));
  // The buffered ticks to the summary and the recording (flushed every flush_period_s of wall time).
  const auto drain = [&] {
    for (int d = 0; d < m; ++d) base.take_ticks(d, pending[d].data(), filled);
    base.flush_if_due();
    filled = 0;
  };

  std::vector<DeviceSample> sent(static_cast<std::size_t>(m));  // the tick's samples, for the monitor
  bool stopped = false;
  for (long k = 0; k < ticks; ++k) {
    // A window's pause holds simulated time; its stop ends the take (scripted devices: no hand to
    // ramp a force out of).
    while (settings.pause && settings.pause->load(std::memory_order_relaxed) && !(settings.stop && settings.stop->load()))
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (settings.stop && settings.stop->load(std::memory_order_relaxed)) {
      stopped = true;
      break;
    }
    for (int d = 0; d < m; ++d) {
      const haptics::DeviceState state = devices[d]->read();
      points[d] = state.position_m, velocities[d] = state.velocity_m_per_s;
    }
    // The tick; after one that started a frame the environment answers at once (lockstep), and
    // its update is held from the next frame's first tick.
    const std::vector<haptics::ContactOutput>& out = session.tick(points, velocities);
    for (int d = 0; d < m; ++d) {
      base.sample(k, points[d], last_points[d], out[d], devices[d]->write(out[d].force), pending[d][filled]);
      last_points[d] = points[d];
      if (settings.monitor) sent[d] = pending[d][filled];
    }
    ++filled;
    if (settings.monitor) publish_tick(*settings.monitor, k + 1, points, out, sent.data(), m);
    // A frame just promoted (its first tick): record the update the tick now holds.
    if (k % settings.loop.ratio == 0 && k > 0) {
      FrameRecord f = frame_record(loop.newest(), k * period);
      add_energy_audit(f, k / settings.loop.ratio - 1, loop.frame_energy());
      base.take_frame(f);
      if (!f.converged && first_failure.empty())
        first_failure = "at " + std::to_string(f.time_s) + " s: " + loop.newest().update.status.message;
      if (settings.after_frame) settings.after_frame(f);
      if (progress) progress->update(k / settings.loop.ratio);
    }
    if (filled == batch) drain();
  }
  drain();
  if (progress) progress->finish();
  SessionSummary summary = base.finish();
  summary.first_failure = first_failure;
  summary.stopped = stopped;
  summary.passivity = passivity_summary(loop);
  summary.identification = identification_summary(loop);
  return summary;
}

}  // namespace fetouch::app
