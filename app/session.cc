#include "app/session.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace fetouch::app {

namespace {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const std::size_t i = static_cast<std::size_t>(std::ceil(p * double(values.size()))) - (p > 0 ? 1 : 0);
  return values[std::min(i, values.size() - 1)];
}

// The frame's row of the recording: the solve's status, the eigenvalues of the condensed normal
// stiffness W_n^-1 and the gains chosen for it.
FrameRecord frame_record(const haptics::FrameSlot& slot, double time_s) {
  FrameRecord f;
  f.frame = slot.update.frame;
  f.time_s = time_s;
  f.solve_s = slot.update.status.seconds;
  f.residual = slot.update.status.residual;
  f.newton_iterations = slot.update.status.iterations;
  f.converged = slot.update.status.converged;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(slot.normal_compliance);
  for (int i = static_cast<int>(eigen.eigenvalues().size()) - 1; i >= 0; --i)
    f.stiffness_eigenvalues.push_back(eigen.eigenvalues()[i] > 0 ? 1 / eigen.eigenvalues()[i] : 0);
  f.proportional_gain = slot.gains.proportional;
  f.integral_gain = slot.gains.integral;
  f.stability_margin = 1 - slot.selection.spectral_radius;
  return f;
}

}  // namespace

SessionSummary run_lockstep(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings) {
  const int m = static_cast<int>(devices.size());
  if (m != environment.contacts())
    throw std::invalid_argument("session: " + std::to_string(m) + " devices for " + std::to_string(environment.contacts()) +
                                " contacts");
  haptics::HapticLoop loop(settings.loop, haptics::initial_update(environment));
  haptics::LockstepSession session(loop, environment);

  std::unique_ptr<RecordingWriter> writer;
  if (settings.recording) {
    RecordingHeader header = settings.header;
    header.probes = settings.probes;
    header.haptic_rate_hz = 1 / settings.loop.period_s;
    header.ratio = settings.loop.ratio;
    writer = std::make_unique<RecordingWriter>(*settings.recording, header);
  }
  const double period = settings.loop.period_s;
  long ticks = settings.max_ticks;
  if (ticks < 0) {
    ticks = 0;
    for (const auto& d : devices) ticks = std::max(ticks, d->ticks());
  }

  // Buffers sized once: the tick loop below only fills them.
  const std::size_t batch = 1000;
  std::vector<std::vector<DeviceSample>> pending(static_cast<std::size_t>(m), std::vector<DeviceSample>(batch));
  std::size_t filled = 0;
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(m)), last_points(static_cast<std::size_t>(m)),
      forces(static_cast<std::size_t>(m), Eigen::Vector3d::Zero());
  std::vector<double> solve_times;
  solve_times.reserve(static_cast<std::size_t>(ticks / settings.loop.ratio + 2));
  SessionSummary summary;
  if (settings.keep_forces)
    summary.forces.assign(static_cast<std::size_t>(m), std::vector<Eigen::Vector3d>(static_cast<std::size_t>(ticks)));
  auto last_flush = std::chrono::steady_clock::now();
  // The buffered ticks to the recording (flushed every flush_period_s of wall time); without a
  // recording they are simply dropped.
  const auto drain = [&] {
    if (writer) {
      for (int d = 0; d < m; ++d) writer->append(d, pending[d].data(), filled);
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - last_flush).count() >= settings.flush_period_s) {
        writer->flush();
        last_flush = std::chrono::steady_clock::now();
      }
    }
    filled = 0;
  };

  for (long k = 0; k < ticks; ++k) {
    for (int d = 0; d < m; ++d) points[d] = devices[d]->next(forces[d]);
    // The tick; after one that started a frame the environment answers at once (lockstep), and
    // its update is held from the next frame's first tick.
    const std::vector<haptics::ContactOutput>& out = session.tick(points);
    for (int d = 0; d < m; ++d) {
      forces[d] = out[d].force;
      if (settings.keep_forces) summary.forces[d][static_cast<std::size_t>(k)] = out[d].force;
      summary.max_force_n = std::max(summary.max_force_n, out[d].force.norm());
      DeviceSample& s = pending[d][filled];
      s.time_s = k * period;
      s.position = points[d];
      s.velocity = k == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d((points[d] - last_points[d]) / period);
      s.force = out[d].force;
      s.proxy = out[d].proxy;
      s.penetration = out[d].penetration;
      s.normal_force = out[d].normal_force;
      s.in_contact = out[d].in_contact;
      last_points[d] = points[d];
    }
    ++filled;
    // A frame just promoted (its first tick): record the update the tick now holds.
    if (k % settings.loop.ratio == 0 && k > 0) {
      const haptics::FrameSlot& held = loop.newest();
      const FrameRecord f = frame_record(held, k * period);
      solve_times.push_back(f.solve_s);
      summary.newton_failures += !f.converged;
      if (settings.loop.schedule_gains) {
        summary.min_stability_margin = std::min(summary.min_stability_margin, f.stability_margin);
        summary.frames_with_unstable_gains += !held.selection.stable;
      }
      ++summary.frames;
      if (writer) writer->append(f);
      if (settings.after_frame) settings.after_frame(f.frame, k * period);
    }
    if (filled == batch) drain();
  }
  drain();
  if (writer) writer->flush();
  summary.ticks = ticks;
  summary.solve_p50_s = percentile(solve_times, 0.5);
  summary.solve_p99_s = percentile(solve_times, 0.99);
  summary.solve_max_s = solve_times.empty() ? 0 : *std::max_element(solve_times.begin(), solve_times.end());
  return summary;
}

}  // namespace fetouch::app
