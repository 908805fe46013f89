// Other programs' share of the CPU (app/machine_load.h): the two /proc files parsed against text
// written here, the arithmetic against a hand count, and live against CPU time measured another
// way: this process's own by the thread's CPU clock, a child's by wait4's rusage.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <thread>

#include "app/machine_load.h"

namespace fetouch::app {
namespace {

double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// Keeps the calling thread busy for `seconds` of its own CPU time.
void spin_cpu(double seconds) {
  const double until = thread_cpu_s() + seconds;
  volatile double x = 0;
  while (thread_cpu_s() < until) x = x + 1;
}

TEST(MachineLoad, ProcStatGivesBusyAndAllTicksAndCountsTheCpus) {
  const std::string text =
      "cpu  100 5 50 800 20 3 2 10 7 0\n"
      "cpu0 50 2 25 400 10 1 1 5 3 0\n"
      "cpu1 50 3 25 400 10 2 1 5 4 0\n"
      "intr 12345 0 0\nctxt 999\nbtime 1700000000\n";
  double busy = 0, all = 0;
  int cpus = 0;
  ASSERT_TRUE(parse_proc_stat(text, busy, all, cpus));
  EXPECT_EQ(busy, 100 + 5 + 50 + 3 + 2 + 10);  // user nice system irq softirq steal; guest is in user
  EXPECT_EQ(all, busy + 800 + 20);              // and idle, iowait
  EXPECT_EQ(cpus, 2);
  EXPECT_FALSE(parse_proc_stat("intr 1 2 3\n", busy, all, cpus));
  EXPECT_FALSE(parse_proc_stat("cpu  1 2\ncpu0 1 2\n", busy, all, cpus));
}

TEST(MachineLoad, OwnStatCountsFieldsFromTheLastParenthesis) {
  // A command name with spaces and a ')' of its own: utime 1234 and stime 56 are fields 14 and 15.
  const std::string text = "4242 (a (b) c) S 1 4242 4242 0 -1 4194560 500 0 0 0 1234 56 0 0 20 0 3 0 100 1000 200\n";
  double own = 0;
  ASSERT_TRUE(parse_own_stat(text, own));
  EXPECT_EQ(own, 1234 + 56);
  EXPECT_FALSE(parse_own_stat("4242 (x) S 1 2 3\n", own));
  EXPECT_FALSE(parse_own_stat("no parenthesis here", own));
}

TEST(MachineLoad, OthersAreTheMachinesBusyTimeLessOursInCores) {
  CpuSample a, b;
  a.valid = b.valid = true;
  a.cpus = b.cpus = 4;
  a.busy_ticks = 1000, a.all_ticks = 4000, a.own_ticks = 300;
  // 100 ticks of wall time on 4 CPUs = 400 ticks in all; 250 busy of which 90 ours: 160 others'.
  b.busy_ticks = 1250, b.all_ticks = 4400, b.own_ticks = 390;
  EXPECT_DOUBLE_EQ(others_cores(a, b), 1.6);
  b.own_ticks = 300 + 250 + 5;  // more own time than busy time (counted at another instant): none
  EXPECT_EQ(others_cores(a, b), 0);
  EXPECT_EQ(others_cores(a, a), 0);  // no time passed
  CpuSample invalid;
  EXPECT_EQ(others_cores(invalid, b), 0);
}

TEST(MachineLoad, OurOwnThreadsAreNotOthers) {
  const CpuSample before = sample_cpu();
  if (!before.valid) GTEST_SKIP() << "/proc/stat or /proc/self/stat cannot be read here";
  double spun = 0;
  std::thread busy([&spun] {
    const double start = thread_cpu_s();
    spin_cpu(0.5);
    spun = thread_cpu_s() - start;
  });
  busy.join();
  const CpuSample after = sample_cpu();
  const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  // Our own time grew by the thread's (the kernel counts in ticks: a few of them either way).
  const double own = (after.own_ticks - before.own_ticks) * tick;
  EXPECT_NEAR(own, spun, 0.05 + 3 * tick);
}

TEST(MachineLoad, AChildKeptBusyCountsAsAnotherProgram) {
  const CpuSample before = sample_cpu();
  if (!before.valid) GTEST_SKIP() << "/proc/stat or /proc/self/stat cannot be read here";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    spin_cpu(0.6);
    _exit(0);
  }
  int status = 0;
  rusage usage{};
  ASSERT_EQ(wait4(child, &status, 0, &usage), child);
  const CpuSample after = sample_cpu();
  const double child_s = usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec + usage.ru_stime.tv_sec + 1e-6 * usage.ru_stime.tv_usec;
  ASSERT_GT(child_s, 0.55);
  const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  const double wall = (after.all_ticks - before.all_ticks) / after.cpus * tick;
  // Others' time is at least the child's (other programs, other tests, may add to it), and none of
  // it is ours: we only waited.
  EXPECT_GE(others_cores(before, after) * wall, child_s - 0.05 - 3 * tick);
  EXPECT_LT((after.own_ticks - before.own_ticks) * tick, 0.05 + 3 * tick);
}

}  // namespace
}  // namespace fetouch::app
