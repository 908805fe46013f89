// A second thread kept for work that comes in pairs: run(a, b) runs a on the calling thread and b on
// the worker at the same time, and returns when both have. Starting a thread for each pair, and
// waking a sleeping one, costs a core's wake-up: on a 2-core VM (2026-12-03) an assembly's two pairs
// lost 530-610 us to thread starts. So each side spins a little before it sleeps: the worker for the
// next pair (an assembly's second follows its first at once), the caller for the worker's half.
// The worker takes the calling thread's cores and nice level before each job, as a thread started by
// it would, so a solver pinned away from the haptic core keeps its helper off it too.
#pragma once

#include <sched.h>

#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace fetouch::fem {

class PairWorker {
 public:
  PairWorker() = default;
  PairWorker(const PairWorker&) = delete;
  PairWorker& operator=(const PairWorker&) = delete;
  ~PairWorker();
  // Both results; an exception from either is rethrown here once both have finished (the caller's
  // first).
  bool run(const std::function<bool()>& here, const std::function<bool()>& there);
  // How long either side spins before it sleeps.
  static constexpr double kSpinSeconds = 200e-6;

 private:
  void loop();
  std::mutex mutex_;
  std::condition_variable cv_;
  // Jobs posted and finished, counted; the job and its outcome are read under the mutex, or after
  // the count that publishes them.
  std::atomic<unsigned long> posted_{0}, finished_{0};
  const std::function<bool()>* job_ = nullptr;
  bool ok_ = false, stop_ = false;
  std::exception_ptr error_;
  cpu_set_t cores_{};  // the caller's, for the next job
  int nice_ = 0;
  std::thread thread_;  // started by the first run
};

}  // namespace fetouch::fem
