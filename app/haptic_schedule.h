// The haptic thread's schedule on the wall clock, shared by real-time sessions (app/session.h) and
// the machine's timing check (`fetouch devices --timing`), so that the check measures the very wait
// the sessions' ticks make: the thread alone on its core (app/realtime_cores.h), real-time scheduled
// (SCHED_FIFO) where the process may, a timer slack of 1 ns, and each deadline slept for up to
// kSpinNs before it, then spun for.
#pragma once

#include <time.h>

#include <vector>

#include "app/realtime_cores.h"

namespace fetouch::app {

double seconds_between(const timespec& from, const timespec& to);
void advance(timespec& t, long nanoseconds);

inline constexpr long kSpinNs = 100'000;  // the haptic thread spins the last 100 us before each deadline

class HapticSchedule {
 public:
  // The first deadline at `origin`, one every `period_ns`.
  HapticSchedule(const timespec& origin, long period_ns) : deadline_(origin), period_ns_(period_ns) {}
  // On the haptic thread, before its first tick: its core (when `cores` has one) and SCHED_FIFO
  // (when `realtime_priority`). Returns whether SCHED_FIFO was granted; core() tells the core.
  bool enter(const CoreSplit& cores, bool realtime_priority);
  int core() const { return core_; }
  // Waits for the current deadline (sleeps, then spins) and returns the time it got there.
  const timespec& wait();
  // The tick done: the next deadline. Returns how far (s) the thread is behind it (> 0: this tick
  // overran into the next period). More than two periods behind (the thread was descheduled), the
  // schedule starts afresh from now rather than run a burst of late ticks.
  double next();
  // A period that is not a tick (a paused session): the deadline moves on without one.
  void skip() { advance(deadline_, period_ns_); }
  const timespec& deadline() const { return deadline_; }

 private:
  timespec deadline_{}, now_{};
  long period_ns_;
  int core_ = -1;
};

// How well this machine keeps the haptic thread's schedule with no work in its ticks: the floor
// under any session's tick lateness (docs/devices.md).
struct TimingCheck {
  long ticks = 0;
  bool realtime_priority = false;  // SCHED_FIFO granted
  int core = -1;                   // the haptic thread's core (-1: not pinned)
  double lateness_p50_s = 0, lateness_p99_s = 0, lateness_max_s = 0;  // of each tick's start after its deadline
  long later_than_100us = 0, later_than_1ms = 0;
  long overruns = 0;  // ticks that ended after the next deadline (what sessions count as late ticks)
  long restarts = 0;  // times the schedule started afresh (more than two periods behind)
};
// Runs the schedule for `duration_s` on a thread of its own, as a real-time session's haptic thread
// would (its core and SCHED_FIFO as asked), each tick doing nothing but note its lateness.
TimingCheck check_haptic_timing(double duration_s, double period_s, bool pin_core, bool realtime_priority);

}  // namespace fetouch::app
