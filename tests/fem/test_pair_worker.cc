// The assembly's kept second thread: both halves of a pair run at once, every pair's results and
// exceptions reach the caller, and the worker runs where (and as nicely as) the caller does.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "fem/pair_worker.h"

namespace {

using fetouch::fem::PairWorker;

cpu_set_t affinity() {
  cpu_set_t set;
  CPU_ZERO(&set);
  pthread_getaffinity_np(pthread_self(), sizeof set, &set);
  return set;
}

TEST(PairWorker, BothHalvesRunAtOnceAndEveryPairsResultsComeBack) {
  PairWorker worker;
  // Each half waits for the other to have started: only two threads at once get past it (a bound
  // on the wait keeps a failure from hanging the suite).
  const auto meet = [](std::atomic<int>& arrived) {
    ++arrived;
    const auto start = std::chrono::steady_clock::now();
    while (arrived.load() < 2)
      if (std::chrono::steady_clock::now() - start > std::chrono::seconds(10)) return false;
    return true;
  };
  for (int pair = 0; pair < 200; ++pair) {
    std::atomic<int> arrived{0};
    ASSERT_TRUE(worker.run([&] { return meet(arrived); }, [&] { return meet(arrived); })) << "pair " << pair;
  }
  int here = 0, there = 0;
  for (int pair = 0; pair < 1000; ++pair) {
    const bool expected = pair % 3 != 0;
    EXPECT_EQ(worker.run([&] { return ++here, true; }, [&] { return ++there, expected; }), expected);
    EXPECT_EQ(worker.run([&] { return ++here, expected; }, [&] { return ++there, true; }), expected);
  }
  EXPECT_EQ(here, 2000);
  EXPECT_EQ(there, 2000);  // each job ran once, and had finished when run() returned
}

TEST(PairWorker, AnExceptionOnEitherSideReachesTheCallerAndTheWorkerGoesOn) {
  PairWorker worker;
  bool other_ran = false;
  EXPECT_THROW(worker.run([&] { return other_ran = true; }, []() -> bool { throw std::runtime_error("there"); }),
               std::runtime_error);
  EXPECT_TRUE(other_ran);
  other_ran = false;
  EXPECT_THROW(worker.run([]() -> bool { throw std::logic_error("here"); }, [&] { return other_ran = true; }),
               std::logic_error);
  EXPECT_TRUE(other_ran);
  EXPECT_TRUE(worker.run([] { return true; }, [] { return true; }));
}

TEST(PairWorker, TheWorkerTakesTheCallersCoresAndNiceLevel) {
  const cpu_set_t all = affinity();
  if (CPU_COUNT(&all) < 2) GTEST_SKIP() << "one core: nothing to pin to";
  // On a thread of its own, so that the test's own thread keeps its cores and nice level.
  std::thread caller([&] {
    PairWorker worker;
    cpu_set_t seen;
    int nice_seen = 0;
    const auto look = [&] {
      seen = affinity();
      nice_seen = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
      return true;
    };
    worker.run([] { return true; }, look);  // started with the caller's cores: all of them
    EXPECT_TRUE(CPU_EQUAL(&seen, &all));
    int first = 0;
    while (!CPU_ISSET(first, &all)) ++first;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof one, &one), 0);
    ASSERT_EQ(setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 7), 0);
    worker.run([] { return true; }, look);
    EXPECT_TRUE(CPU_EQUAL(&seen, &one)) << "the worker still runs on " << CPU_COUNT(&seen) << " cores";
    EXPECT_EQ(nice_seen, 7);
    ASSERT_EQ(pthread_setaffinity_np(pthread_self(), sizeof all, &all), 0);
    worker.run([] { return true; }, look);
    EXPECT_TRUE(CPU_EQUAL(&seen, &all));
  });
  caller.join();
}

}  // namespace
