#include "fem/pair_worker.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>

namespace fetouch::fem {

namespace {
pid_t thread_id() { return static_cast<pid_t>(syscall(SYS_gettid)); }

// Spins until `ready` holds or kSpinSeconds have passed; whether it holds.
template <class Ready>
bool spin(const Ready& ready) {
  const auto start = std::chrono::steady_clock::now();
  const auto limit = std::chrono::duration<double>(PairWorker::kSpinSeconds);
  for (int i = 0;; ++i) {
    if (ready()) return true;
    if (i % 64 == 63 && std::chrono::steady_clock::now() - start > limit) return ready();
  }
}
}  // namespace

PairWorker::~PairWorker() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool PairWorker::run(const std::function<bool()>& here, const std::function<bool()>& there) {
  cpu_set_t cores;
  CPU_ZERO(&cores);
  const bool pinned = pthread_getaffinity_np(pthread_self(), sizeof cores, &cores) == 0;
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(thread_id()));
  unsigned long job = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pinned) cores_ = cores;
    nice_ = errno == 0 ? nice : 0;
    job_ = &there, error_ = nullptr;
    job = posted_.load() + 1;
    posted_.store(job, std::memory_order_release);
  }
  if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
  cv_.notify_all();
  bool here_ok = false;
  std::exception_ptr here_error;
  try {
    here_ok = here();
  } catch (...) {
    here_error = std::current_exception();
  }
  const auto done = [&] { return finished_.load(std::memory_order_acquire) == job; };
  spin(done);
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, done);
  if (here_error) std::rethrow_exception(here_error);
  if (error_) std::rethrow_exception(error_);
  return here_ok && ok_;
}

void PairWorker::loop() {
  cpu_set_t applied_cores;
  CPU_ZERO(&applied_cores);
  int applied_nice = 0;
  bool first = true;
  unsigned long taken = 0;
  const auto posted = [&] { return posted_.load(std::memory_order_acquire) != taken; };
  for (;;) {
    if (!first) spin(posted);
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return stop_ || posted(); });
    if (stop_) return;
    taken = posted_.load();
    const std::function<bool()>* job = job_;
    if (first || !CPU_EQUAL(&cores_, &applied_cores)) {
      if (CPU_COUNT(&cores_) > 0) pthread_setaffinity_np(pthread_self(), sizeof cores_, &cores_);
      applied_cores = cores_;
    }
    if (first || nice_ != applied_nice) {
      setpriority(PRIO_PROCESS, static_cast<id_t>(thread_id()), nice_);
      applied_nice = nice_;
    }
    first = false;
    lock.unlock();
    bool ok = false;
    std::exception_ptr error;
    try {
      ok = (*job)();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    ok_ = ok, error_ = error;
    finished_.store(taken, std::memory_order_release);
    lock.unlock();
    cv_.notify_all();
  }
}

}  // namespace fetouch::fem
