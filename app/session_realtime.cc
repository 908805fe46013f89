// run_realtime (app/session.h): the haptic, solver and I/O threads on the wall clock.
#include "app/session.h"

#include <pthread.h>
#include <sched.h>
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

#include "app/session_base.h"
#include "app/session_rows.h"
#include "app/haptic_schedule.h"
#include "app/realtime_cores.h"
#include "haptics/lock_free.h"

namespace fetouch::app {

using detail::SessionBase;
using detail::spread;

namespace {

// The samples of one frame, from the haptic thread to the solver thread.
struct FrameRequest {
  long frame = -1;
  std::vector<haptics::ContactSample> samples;
  std::vector<haptics::FrameEnergy> energy;  // the audit of the frame before `frame`
};

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
  HapticSchedule schedule(origin, period_ns);
  timespec now{};
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
                        : seconds_between(schedule.deadline(), now);
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
    priority_granted = schedule.enter(cores, settings.realtime_priority);
    haptic_core = schedule.core();
    for (bool more = true; more;) {
      schedule.wait();
      if (settings.pause && settings.pause->load(std::memory_order_relaxed) &&
          !(settings.stop && settings.stop->load(std::memory_order_relaxed)) && !stopping.load(std::memory_order_relaxed)) {
        schedule.skip();  // paused: this period is not a tick
        paused_s += period;
        continue;
      }
      more = tick();
      if (schedule.next() > 0) tick_overruns.fetch_add(1, std::memory_order_relaxed);
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
