// What a thread of this process may do with its priority (tests of the real-time sessions' nice
// values): a fresh thread's nice, and whether it may raise itself to `wanted`. The answer depends on
// the machine (root, CAP_SYS_NICE, RLIMIT_NICE), so the tests expect what it says.
#pragma once

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <thread>

namespace fetouch::testing {

struct NiceRights {
  int started = 0;    // a fresh thread's nice
  bool may = false;   // it could set `wanted`
  int expected(int wanted) const { return may ? wanted : started; }  // what a raise leaves it at
};

inline NiceRights nice_rights(int wanted) {
  NiceRights rights;
  std::thread probe([&] {
    const auto tid = static_cast<id_t>(syscall(SYS_gettid));
    rights.started = getpriority(PRIO_PROCESS, tid);
    setpriority(PRIO_PROCESS, tid, wanted);
    rights.may = getpriority(PRIO_PROCESS, tid) == wanted;
  });
  probe.join();
  return rights;
}

}  // namespace fetouch::testing
