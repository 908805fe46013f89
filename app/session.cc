#include "app/session.h"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <iostream>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "app/progress.h"
#include "app/session_rows.h"
#include "app/realtime_cores.h"
#include "haptics/lock_free.h"

namespace fetouch::app {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(p * double(values.size())));
  return values[std::min(rank == 0 ? 0 : rank - 1, values.size() - 1)];
}

namespace {

// The median, 99th percentile and largest of `values` (zeros when there are none).
void spread(const std::vector<double>& values, double& p50, double& p99, double& max) {
  p50 = percentile(values, 0.5), p99 = percentile(values, 0.99), max = percentile(values, 1);
}


// What both clocks share: the checks, the recording, the number of ticks, and the summary's
// per-frame and per-tick figures.
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


}  // namespace

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

namespace {

// The samples of one frame, from the haptic thread to the solver thread.
struct FrameRequest {
  long frame = -1;
  std::vector<haptics::ContactSample> samples;
  std::vector<haptics::FrameEnergy> energy;  // the audit of the frame before `frame`
};

double seconds_between(const timespec& from, const timespec& to) {
  return double(to.tv_sec - from.tv_sec) + 1e-9 * double(to.tv_nsec - from.tv_nsec);
}

void advance(timespec& t, long nanoseconds) {
  t.tv_nsec += nanoseconds;
  while (t.tv_nsec >= 1000000000L) t.tv_nsec -= 1000000000L, ++t.tv_sec;
  while (t.tv_nsec < 0) t.tv_nsec += 1000000000L, --t.tv_sec;
}

constexpr long kSpinNs = 100'000;  // the haptic thread spins the last 100 us before each deadline
constexpr double kRampOutS = 0.2;  // a stopped session's force ramps out over this time

}  // namespace

SessionSummary run_realtime(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings) {
  SessionBase base(environment, devices, settings);
  haptics::HapticLoop loop(settings.loop, haptics::initial_update(environment));
  const int m = base.devices();
  const long ticks = base.ticks();
  const double period = settings.loop.period_s;
  const long period_ns = std::lround(period * 1e9);

  haptics::TripleBuffer<FrameRequest> requests(
      FrameRequest{-1, std::vector<haptics::ContactSample>(m), std::vector<haptics::FrameEnergy>(m)});
  // Four seconds of ticks: the I/O thread drains it every few milliseconds.
  haptics::SpscRing<DeviceSample> ring(static_cast<std::size_t>(m) * 4096);
  std::vector<double> starts(static_cast<std::size_t>(ticks)), lateness(static_cast<std::size_t>(ticks));
  std::atomic<bool> haptic_done{false}, solver_done{false}, stopping{false};
  std::atomic<long> skipped{0}, dropped{0}, tick_overruns{0};
  std::atomic<bool> priority_granted{false};
  long ran = 0;  // ticks the haptic thread ran (read after it joined)
  // Frames the solver answered otherwise than lockstep would, and the first (read after it joined).
  long differing_frames = 0, first_differing_frame = -1;
  std::mutex frames_mutex;  // between the solver and I/O threads only
  std::vector<FrameRecord> frames;
  std::exception_ptr solver_error, io_error, haptic_error;

  timespec origin{};
  clock_gettime(CLOCK_MONOTONIC, &origin);
  advance(origin, 20'000'000);  // the first tick 20 ms from now, once the threads are up

  const CoreSplit cores = CoreSplit::make(settings.pin_haptic_core);
  std::atomic<int> haptic_core{-1};
  // Stopping (a request, or a device's fault): the force ramps out over kRampOutS in the loop's
  // safety layer (what the hand is sent and the tissue is pressed with fade together), then the
  // session ends. A fault is reported once the threads have joined.
  const long ramp_out_ticks = std::max<long>(1, std::lround(kRampOutS / period));
  long stop_tick = -1;
  const char* fault = nullptr;
  int fault_device = -1;
  SessionMonitor* const monitor = settings.monitor;
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(m)), last(static_cast<std::size_t>(m));
  std::vector<Eigen::Vector3d> velocities(static_cast<std::size_t>(m));
  std::vector<DeviceSample> block(static_cast<std::size_t>(m));
  timespec deadline = origin, now{};
  double previous_start = -1;
  double paused_s = 0;  // wall-clock time spent paused, left out of the tick starts
  haptics::ServoClock* servo = nullptr;
  for (const auto& d : devices)
    if (!servo) servo = d->servo_clock();
  // One tick, on the haptic thread's clock or in a driver's servo callback; false: the session is over.
  long k = 0;
  const auto tick = [&]() noexcept -> bool {
    if (k >= ticks) return false;
    clock_gettime(CLOCK_MONOTONIC, &now);
    starts[k] = seconds_between(origin, now) - paused_s;
    // On a driver's clock, a tick is late when it starts more than a period after the last one.
    lateness[k] = servo ? (previous_start < 0 ? 0 : std::max(0.0, starts[k] - previous_start - period))
                        : seconds_between(deadline, now);
    previous_start = starts[k];
    if (servo && k == 0 && cores.pin_haptic()) haptic_core = cores.haptic;  // the driver's thread, on the haptic core
    if (servo && lateness[k] > 0.5 * period) tick_overruns.fetch_add(1, std::memory_order_relaxed);
    for (int d = 0; d < m; ++d) {
      const haptics::DeviceState state = devices[d]->read();
      points[d] = state.position_m, velocities[d] = state.velocity_m_per_s;
    }
    if (stop_tick < 0 && settings.stop && settings.stop->load(std::memory_order_relaxed)) stop_tick = k;
    for (int d = 0; d < m && stop_tick < 0; ++d)
      if (const char* f = devices[d]->fault()) fault = f, fault_device = d, stop_tick = k;
    if (stop_tick == k) loop.ramp_out(ramp_out_ticks);  // the loop's safety layer fades the force from this tick
    const std::vector<haptics::ContactOutput>& out = loop.tick(points, velocities);
    for (int d = 0; d < m; ++d) {
      base.sample(k, points[d], last[d], out[d], devices[d]->write(out[d].force), block[d]);
      last[d] = points[d];
    }
    if (monitor) {
      publish_tick(*monitor, k + 1, points, out, block.data(), m);
      monitor->late_ticks.store(tick_overruns.load(std::memory_order_relaxed), std::memory_order_relaxed);
    }
    if (!ring.push(block.data(), block.size())) dropped.fetch_add(1, std::memory_order_relaxed);
    if (loop.decimated()) {
      FrameRequest& r = requests.back();
      r.frame = loop.frame();
      std::copy(loop.samples().begin(), loop.samples().end(), r.samples.begin());
      std::copy(loop.frame_energy().begin(), loop.frame_energy().end(), r.energy.begin());
      if (!requests.publish()) skipped.fetch_add(1, std::memory_order_relaxed);
    }
    ran = ++k;
    return k < ticks && !stopping.load(std::memory_order_relaxed) && !loop.ramped_out();
  };
  std::thread haptic([&] {
    if (servo) {
      // The driver's servo thread runs the ticks; this thread waits for the session's end.
      using Tick = decltype(tick);
      std::atomic<bool> over{false};
      struct Context {
        Tick* tick;
        std::atomic<bool>* over;
      } context{&tick, &over};
      try {
        servo->start(
            [](void* c) noexcept {
              auto* x = static_cast<Context*>(c);
              if (x->over->load(std::memory_order_relaxed)) return false;
              if (!(*x->tick)()) x->over->store(true);
              return !x->over->load(std::memory_order_relaxed);
            },
            &context);
      } catch (...) {
        haptic_error = std::current_exception();
        stopping = true;
      }
      while (!haptic_error && !over.load() && !stopping.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      servo->stop();
      haptic_done = true;
      return;
    }
    if (cores.pin_haptic()) haptic_core = cores.haptic;
    if (settings.realtime_priority) {
      sched_param p{};
      p.sched_priority = std::min(80, sched_get_priority_max(SCHED_FIFO));
      priority_granted = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
    }
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);  // wake-ups on time, not up to 50 us late
    timespec wake{};
    for (bool more = true; more;) {
      // Sleep to just before the deadline, then spin the last stretch: the sleep's own wake-up
      // latency (tens of microseconds on a virtual machine) is spent spinning, not late.
      wake = deadline;
      advance(wake, -kSpinNs);
      while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) != 0) {
      }
      do clock_gettime(CLOCK_MONOTONIC, &now);
      while (seconds_between(deadline, now) < 0);
      if (settings.pause && settings.pause->load(std::memory_order_relaxed) &&
          !(settings.stop && settings.stop->load(std::memory_order_relaxed)) && !stopping.load(std::memory_order_relaxed)) {
        advance(deadline, period_ns);  // paused: this period is not a tick
        paused_s += period;
        continue;
      }
      more = tick();
      advance(deadline, period_ns);
      clock_gettime(CLOCK_MONOTONIC, &now);
      const double behind = seconds_between(deadline, now);
      if (behind > 0) tick_overruns.fetch_add(1, std::memory_order_relaxed);
      // More than two periods behind (the thread was descheduled): start the schedule afresh
      // rather than run a burst of late ticks.
      if (behind > 2 * period) deadline = now;
    }
    haptic_done = true;
  });

  std::atomic<int> solver_nice{0};
  std::thread solver([&] {
    cores.pin_other();
    // Before the solves, so that the threads a frame starts inherit it and the background
    // factoriser's nice follows it (app/realtime_cores.h).
    solver_nice = settings.realtime_priority ? raise_solver_priority() : thread_nice();
    if (monitor) monitor->solver_nice.store(solver_nice.load(), std::memory_order_relaxed);
    try {
      for (;;) {
        if (!requests.take()) {
          if (haptic_done.load() || stopping.load()) break;
          std::this_thread::sleep_for(std::chrono::microseconds(200));
          continue;
        }
        const FrameRequest& r = requests.front();
        const haptics::FrameSlot& slot = loop.fill_answer(environment, r.samples, r.frame);
        if (slot.update.status.differs_from_lockstep && differing_frames++ == 0) first_differing_frame = r.frame;
        timespec answered{};
        clock_gettime(CLOCK_MONOTONIC, &answered);
        const double arrived = seconds_between(origin, answered);
        FrameRecord f = frame_record(slot, arrived);
        if (r.frame > 0) add_energy_audit(f, r.frame - 1, r.energy);
        loop.publish();
        {
          std::lock_guard<std::mutex> lock(frames_mutex);
          frames.push_back(f);
        }
        if (settings.after_frame) settings.after_frame(f);
      }
    } catch (...) {
      solver_error = std::current_exception();
      stopping = true;
    }
    solver_done = true;
  });

  std::thread io([&] {
    cores.pin_other();
    try {
      const std::size_t batch = 1024;
      std::vector<DeviceSample> popped(batch * static_cast<std::size_t>(m));
      std::vector<std::vector<DeviceSample>> per_device(static_cast<std::size_t>(m), std::vector<DeviceSample>(batch));
      std::vector<FrameRecord> taken;
      for (;;) {
        const bool finished = haptic_done.load() && solver_done.load();
        const std::size_t n = ring.pop(popped.data(), popped.size()) / static_cast<std::size_t>(m);
        for (int d = 0; d < m; ++d) {
          for (std::size_t i = 0; i < n; ++i) per_device[d][i] = popped[i * m + d];
          base.take_ticks(d, per_device[d].data(), n);
        }
        {
          std::lock_guard<std::mutex> lock(frames_mutex);
          taken.swap(frames);
        }
        for (const FrameRecord& f : taken) base.take_frame(f);
        taken.clear();
        base.flush_if_due();
        if (finished && n == 0) break;
        if (n < batch) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    } catch (...) {
      io_error = std::current_exception();
      stopping = true;
    }
  });

  haptic.join();
  solver.join();
  io.join();
  if (haptic_error) std::rethrow_exception(haptic_error);
  if (solver_error) std::rethrow_exception(solver_error);
  if (io_error) std::rethrow_exception(io_error);

  SessionSummary summary = base.finish();
  if (fault) summary.fault = fault, summary.fault_device = fault_device;
  summary.ticks = ran;
  summary.stopped = stop_tick >= 0;
  for (const auto& d : devices) summary.recoverable_errors.push_back(d->recoverable_errors());
  summary.passivity = passivity_summary(loop);
  summary.identification = identification_summary(loop);
  TimingSummary& t = summary.timing;
  starts.resize(static_cast<std::size_t>(ran));
  lateness.resize(static_cast<std::size_t>(ran));
  std::vector<double> periods;
  for (std::size_t i = 1; i < starts.size(); ++i) periods.push_back(starts[i] - starts[i - 1]);
  spread(periods, t.period_p50_s, t.period_p99_s, t.period_max_s);
  spread(lateness, t.lateness_p50_s, t.lateness_p99_s, t.lateness_max_s);
  t.tick_overruns = tick_overruns;
  t.frame_overruns = loop.late_answers();
  t.first_late_tick = loop.first_late_tick();
  t.solver_differences = differing_frames;
  // That frame's answer is taken up at the next frame's start at the earliest.
  t.first_solver_difference_tick = first_differing_frame < 0 ? -1 : (first_differing_frame + 1) * settings.loop.ratio;
  t.skipped_frames = skipped;
  t.dropped_samples = dropped;
  t.realtime_priority = priority_granted;
  t.solver_nice = solver_nice;
  t.haptic_core = haptic_core;
  return summary;
}

}  // namespace fetouch::app
