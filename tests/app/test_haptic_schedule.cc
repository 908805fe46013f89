// The haptic thread's schedule (app/haptic_schedule.h), which real-time sessions and `fetouch
// devices --timing` share: no tick starts before its deadline (checked on the steady clock, not the
// schedule's own), lateness is counted as the ticks' starts say, and a thread that falls more than
// two periods behind starts its schedule afresh while a smaller overrun keeps the cadence.
#include <gtest/gtest.h>
#include <time.h>

#include <chrono>
#include <thread>

#include "app/haptic_schedule.h"

namespace fetouch::app {
namespace {

timespec monotonic_now() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t;
}

TEST(HapticSchedule, TheCheckRunsEveryTickAndNoneStartsBeforeItsDeadline) {
  const auto start = std::chrono::steady_clock::now();
  const TimingCheck t = check_haptic_timing(0.2, 1e-3, /*pin_core=*/true, /*realtime_priority=*/true);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(t.ticks, 200);
  // The first deadline is 20 ms after the start and the last tick starts at or after its own, so
  // the check cannot take less than 20 ms + 199 periods (a wait that returned early would).
  EXPECT_GE(took, 0.020 + 0.199);
  EXPECT_GE(t.lateness_p50_s, 0.0);
  EXPECT_LE(t.lateness_p50_s, t.lateness_p99_s);
  EXPECT_LE(t.lateness_p99_s, t.lateness_max_s);
  EXPECT_LE(t.later_than_1ms, t.later_than_100us);
  EXPECT_LE(t.later_than_100us, t.ticks);
  EXPECT_EQ(t.later_than_1ms > 0, t.lateness_max_s > 1e-3);
  EXPECT_LE(t.restarts, t.overruns);
}

TEST(HapticSchedule, AnOverrunKeepsTheCadenceUnlessTheThreadFellTwoPeriodsBehind) {
  const long period_ns = 1'000'000;
  for (const double overrun_s : {0.0015, 0.006}) {
    timespec origin = monotonic_now();
    advance(origin, 2'000'000);
    HapticSchedule schedule(origin, period_ns);
    const timespec& woke = schedule.wait();
    EXPECT_GE(seconds_between(origin, woke), 0.0);
    std::this_thread::sleep_for(std::chrono::duration<double>(overrun_s));  // a tick that overran
    const timespec before = monotonic_now();
    const double behind = schedule.next();
    const timespec after = monotonic_now();
    // How far behind the next deadline (origin + 1 period) the thread is, by the clock read here.
    const double expected_low = seconds_between(origin, before) - 1e-3;
    const double expected_high = seconds_between(origin, after) - 1e-3;
    EXPECT_GE(behind, expected_low) << overrun_s;
    EXPECT_LE(behind, expected_high) << overrun_s;
    EXPECT_GT(behind, 0.0) << overrun_s;
    if (behind > 2e-3) {  // afresh: the next deadline is now
      EXPECT_GE(seconds_between(before, schedule.deadline()), 0.0) << overrun_s;
      EXPECT_LE(seconds_between(schedule.deadline(), after), 1e-3) << overrun_s;
      EXPECT_GE(seconds_between(schedule.deadline(), after), 0.0) << overrun_s;
    } else {  // the cadence kept: the next deadline is one period on from the first
      EXPECT_NEAR(seconds_between(origin, schedule.deadline()), 1e-3, 1e-12) << overrun_s;
    }
  }
}

TEST(HapticSchedule, APausedPeriodMovesTheDeadlineOnWithoutATick) {
  timespec origin{5, 999'500'000};
  HapticSchedule schedule(origin, 1'000'000);
  schedule.skip();
  schedule.skip();
  EXPECT_EQ(schedule.deadline().tv_sec, 6);
  EXPECT_EQ(schedule.deadline().tv_nsec, 1'500'000);
  EXPECT_THROW(check_haptic_timing(0, 1e-3, false, false), std::invalid_argument);
  EXPECT_THROW(check_haptic_timing(1, -1e-3, false, false), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::app
