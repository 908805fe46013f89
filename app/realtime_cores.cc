#include "app/realtime_cores.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>

#include "app/session.h"

namespace fetouch::app {

namespace {

// The cores the process may use, as they were before share_haptic_core() narrowed the calling
// thread's (and so its children's) set.
bool g_cores_saved = false;
cpu_set_t g_cores;

}  // namespace

bool allowed_cores(cpu_set_t& allowed) {
  if (g_cores_saved) {
    allowed = g_cores;
    return true;
  }
  return sched_getaffinity(0, sizeof allowed, &allowed) == 0;
}

CoreSplit CoreSplit::make(bool wanted) {
  CoreSplit split;
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (!wanted || !allowed_cores(allowed) || CPU_COUNT(&allowed) < 2) return split;
  for (int c = CPU_SETSIZE - 1; c >= 0; --c)
    if (CPU_ISSET(c, &allowed)) {
      split.haptic = c;
      break;
    }
  split.others = allowed;
  CPU_CLR(split.haptic, &split.others);
  return split;
}

bool CoreSplit::pin_haptic() const {
  if (haptic < 0) return false;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(haptic, &one);
  return pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
}

void CoreSplit::pin_other() const {
  if (haptic >= 0) pthread_setaffinity_np(pthread_self(), sizeof others, &others);
}

int realtime_solver_cores(const SessionSettings& settings) {
  const CoreSplit split = CoreSplit::make(settings.pin_haptic_core);
  if (split.haptic >= 0) return CPU_COUNT(&split.others);
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  return allowed_cores(allowed) ? CPU_COUNT(&allowed) : 1;
}

int thread_nice() {
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));  // -1 is valid: errno tells
  return errno == 0 ? nice : 0;
}

int raise_thread_priority(int nice) {
  if (thread_nice() > nice)  // refused without the right: the thread keeps its nice
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice);
  return thread_nice();
}

void share_haptic_core() {
  const CoreSplit split = CoreSplit::make(true);
  if (split.haptic < 0) return;
  sched_getaffinity(0, sizeof g_cores, &g_cores);
  g_cores_saved = true;
  split.pin_haptic();
}

}  // namespace fetouch::app
