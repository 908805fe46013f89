// TangentSystem's background factoriser (internal to fem/: tangent_system.cc creates and destroys
// it, tangent_system_cholmod.cc drives it): a thread with a CHOLMOD factor of its own, fed a
// snapshot of K's values. Only the solver thread talks to it (the haptic tick never does).
#pragma once

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "fem/cholesky_factor.h"
#include "fem/tangent_system.h"

namespace fetouch::fem {

void limit_library_threads();  // one thread inside CHOLMOD's OpenMP and OpenBLAS (tangent_system.cc)

struct TangentSystem::Worker {
  std::unique_ptr<CholeskyFactor> factor;
  std::vector<double> values;
  // A request made while the warm-up factorisation ran: its values, factorised as soon as that ends.
  std::vector<double> queued_values;
  bool queued = false;
  std::mutex mutex;
  std::condition_variable cv;
  bool requested = false, done = false, ok = false, stop = false;
  cpu_set_t affinity{};  // the requesting thread's cores: the worker runs where the solver may
  bool pinned = false;
  // Real time (frames taken up when ready): the worker yields the core it shares with the solver
  // to the frames, which have a deadline, and factorises in the time they leave (19 nice levels
  // below the solver thread, at most 19: background_nice in tangent_system_cholmod.cc).
  int nice = 0, applied_nice = 0;
  std::thread thread;

  Worker(int n, const int* row_start, const int* columns)
      : factor(std::make_unique<CholeskyFactor>(n, row_start, columns)), thread([this] { run(); }) {}
  ~Worker() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    cv.notify_all();
    thread.join();
  }
  void run() {
    limit_library_threads();
    std::unique_lock<std::mutex> lock(mutex);
    for (;;) {
      cv.wait(lock, [this] { return stop || (requested && !done); });
      if (stop) return;
      if (pinned) pthread_setaffinity_np(pthread_self(), sizeof affinity, &affinity);
      if (nice != applied_nice) {
        setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice);
        applied_nice = nice;
      }
      lock.unlock();
      const bool success = factor->factorise(values.data());
      lock.lock();
      if (queued) {  // that was the warm-up, asked for again meanwhile: on to the request, still not done
        values.swap(queued_values);
        queued = false;
        continue;
      }
      ok = success, done = true;
      cv.notify_all();
    }
  }
};


}  // namespace fetouch::fem
