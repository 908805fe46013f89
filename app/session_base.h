// What a lockstep and a real-time session share (app/session.h; internal to session.cc and
// session_realtime.cc): the checks, the recording, the number of ticks, and the summary's per-frame
// and per-tick figures.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/session.h"
#include "app/session_rows.h"

namespace fetouch::app::detail {

// The median, 99th percentile and largest of `values` (zeros when there are none).
inline void spread(const std::vector<double>& values, double& p50, double& p99, double& max) {
  p50 = percentile(values, 0.5), p99 = percentile(values, 0.99), max = percentile(values, 1);
}

class SessionBase {
 public:
  SessionBase(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
              const SessionSettings& settings)
      : settings_(settings), m_(static_cast<int>(devices.size())) {
    if (m_ != environment.contacts())
      throw std::invalid_argument("session: " + std::to_string(m_) + " devices for " +
                                  std::to_string(environment.contacts()) + " contacts");
    if (settings.recording) {
      RecordingHeader header = settings.header;
      header.probes = settings.probes;
      header.haptic_rate_hz = 1 / settings.loop.period_s;
      header.ratio = settings.loop.ratio;
      writer_ = std::make_unique<RecordingWriter>(*settings.recording, header);
    }
    ticks_ = settings.max_ticks;
    if (ticks_ < 0) {
      ticks_ = 0;
      for (const auto& d : devices) ticks_ = std::max(ticks_, d->ticks());
    }
    summary_.ticks = ticks_;
    if (settings.keep_forces) {
      summary_.forces.assign(static_cast<std::size_t>(m_), std::vector<Eigen::Vector3d>(static_cast<std::size_t>(ticks_)));
      summary_.positions = summary_.forces;
    }
    solve_times_.reserve(static_cast<std::size_t>(ticks_ / settings.loop.ratio + 2));
    last_flush_ = std::chrono::steady_clock::now();
  }

  long ticks() const { return ticks_; }
  int devices() const { return m_; }

  // One device's tick as recorded (tick k; `last` is its point at tick k - 1).
  // `sent`: the force the device was given (Device::write's answer).
  void sample(long k, const Eigen::Vector3d& point, const Eigen::Vector3d& last, const haptics::ContactOutput& out,
              const Eigen::Vector3d& sent, DeviceSample& s) const {
    const double period = settings_.loop.period_s;
    s.time_s = k * period;
    s.position = point;
    s.velocity = k == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d((point - last) / period);
    s.force = sent;
    s.proxy = out.proxy;
    s.penetration = out.penetration;
    s.normal_force = out.normal_force;
    s.in_contact = out.in_contact;
    s.port_energy_j = out.port_energy_j;
    s.passivity_scale = out.passivity_scale;
    s.controller_force = out.controller_force;
    s.identified_stiffness_n_per_m = out.identified ? out.identified_stiffness_n_per_m : 0.0;
    s.identified_damping_n_s_per_m = out.identified ? out.identified_damping_n_s_per_m : 0.0;
    s.condensed_stiffness_n_per_m = out.condensed_stiffness_n_per_m;
  }

  // Ticks to the summary and the recording: `count` ticks of device d.
  void take_ticks(int d, const DeviceSample* samples, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      summary_.max_force_n = std::max(summary_.max_force_n, samples[i].force.norm());
      if (settings_.keep_forces) {
        const long k = std::lround(samples[i].time_s / settings_.loop.period_s);
        if (k >= 0 && k < ticks_) {
          summary_.forces[d][static_cast<std::size_t>(k)] = samples[i].force;
          summary_.positions[d][static_cast<std::size_t>(k)] = samples[i].position;
        }
      }
    }
    if (writer_) writer_->append(d, samples, count);
  }

  void take_frame(const FrameRecord& f) {
    solve_times_.push_back(f.solve_s);
    summary_.newton_failures += !f.converged;
    summary_.min_stability_margin = std::min(summary_.min_stability_margin, f.stability_margin);
    summary_.frames_with_unstable_gains += !(f.stability_margin > 0);  // radius >= 1: not robustly stable
    const auto largest = [](const std::vector<double>& v) { return v.empty() ? -1.0 : *std::max_element(v.begin(), v.end()); };
    if (largest(f.stiffness_eigenvalues) > largest(summary_.stiffest_eigenvalues)) {
      summary_.stiffest_eigenvalues = f.stiffness_eigenvalues;
      summary_.stiffest_proportional_gain = f.proportional_gain, summary_.stiffest_integral_gain = f.integral_gain;
      summary_.stiffest_local_model = f.local_model, summary_.stiffest_hold = f.hold;
    }
    ++summary_.frames;
    if (writer_) writer_->append(f);
  }

  // Flushes the recording when flush_period_s of wall time has passed since the last flush.
  void flush_if_due() {
    if (!writer_) return;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_flush_).count() >= settings_.flush_period_s) {
      writer_->flush();
      last_flush_ = now;
    }
  }

  SessionSummary finish() {
    if (writer_) writer_->commit();
    spread(solve_times_, summary_.solve_p50_s, summary_.solve_p99_s, summary_.solve_max_s);
    return std::move(summary_);
  }

  SessionSummary& summary() { return summary_; }

 private:
  const SessionSettings& settings_;
  int m_;
  long ticks_ = 0;
  std::unique_ptr<RecordingWriter> writer_;
  std::vector<double> solve_times_;
  SessionSummary summary_;
  std::chrono::steady_clock::time_point last_flush_;
};

}  // namespace fetouch::app::detail
