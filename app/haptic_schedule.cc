#include "app/haptic_schedule.h"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

namespace fetouch::app {

double seconds_between(const timespec& from, const timespec& to) {
  return double(to.tv_sec - from.tv_sec) + 1e-9 * double(to.tv_nsec - from.tv_nsec);
}

void advance(timespec& t, long nanoseconds) {
  t.tv_nsec += nanoseconds;
  while (t.tv_nsec >= 1000000000L) t.tv_nsec -= 1000000000L, ++t.tv_sec;
  while (t.tv_nsec < 0) t.tv_nsec += 1000000000L, --t.tv_sec;
}

bool HapticSchedule::enter(const CoreSplit& cores, bool realtime_priority) {
  if (cores.pin_haptic()) core_ = cores.haptic;
  bool granted = false;
  if (realtime_priority) {
    sched_param p{};
    p.sched_priority = std::min(80, sched_get_priority_max(SCHED_FIFO));
    granted = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
  }
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);  // wake-ups on time, not up to 50 us late
  return granted;
}

const timespec& HapticSchedule::wait() {
  // Sleep to just before the deadline, then spin the last stretch: the sleep's own wake-up latency
  // (tens of microseconds on a virtual machine) is spent spinning, not late.
  timespec wake = deadline_;
  advance(wake, -kSpinNs);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr) != 0) {
  }
  do clock_gettime(CLOCK_MONOTONIC, &now_);
  while (seconds_between(deadline_, now_) < 0);
  return now_;
}

double HapticSchedule::next() {
  advance(deadline_, period_ns_);
  clock_gettime(CLOCK_MONOTONIC, &now_);
  const double behind = seconds_between(deadline_, now_);
  if (behind > 2e-9 * double(period_ns_)) deadline_ = now_;
  return behind;
}

TimingCheck check_haptic_timing(double duration_s, double period_s, bool pin_core, bool realtime_priority) {
  if (!(duration_s > 0) || !(period_s > 0) || duration_s / period_s > 1e8)
    throw std::invalid_argument("timing check: a positive duration and period (and at most 10^8 ticks)");
  const long ticks = std::max(1L, std::lround(duration_s / period_s));
  const long period_ns = std::max(1L, std::lround(period_s * 1e9));
  std::vector<double> lateness(static_cast<std::size_t>(ticks));
  TimingCheck check;
  const CoreSplit cores = CoreSplit::make(pin_core);
  std::thread haptic([&] {
    timespec origin{};
    clock_gettime(CLOCK_MONOTONIC, &origin);
    advance(origin, 20'000'000);  // as a session: the first tick 20 ms on
    HapticSchedule schedule(origin, period_ns);
    check.realtime_priority = schedule.enter(cores, realtime_priority);
    check.core = schedule.core();
    for (long k = 0; k < ticks; ++k) {
      const timespec& now = schedule.wait();
      lateness[static_cast<std::size_t>(k)] = seconds_between(schedule.deadline(), now);
      const double behind = schedule.next();
      if (behind > 0) ++check.overruns;
      if (behind > 2 * period_s) ++check.restarts;
    }
  });
  haptic.join();
  check.ticks = ticks;
  for (const double l : lateness) check.later_than_100us += l > 1e-4, check.later_than_1ms += l > 1e-3;
  std::sort(lateness.begin(), lateness.end());
  const auto at = [&](double q) { return lateness[std::min(lateness.size() - 1, std::size_t(q * double(lateness.size())))]; };
  check.lateness_p50_s = at(0.5), check.lateness_p99_s = at(0.99), check.lateness_max_s = lateness.back();
  return check;
}

}  // namespace fetouch::app
