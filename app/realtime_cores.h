// How a real-time session shares the machine's cores (app/session.h): the haptic thread alone on the
// last core the process may use, the solver and I/O threads (and the threads they start) on the
// others; none of this with fewer than 2 cores.
#pragma once

#include <sched.h>

namespace fetouch::app {

struct CoreSplit {
  int haptic = -1;  // the haptic thread's core (-1: not pinned)
  cpu_set_t others{};
  // The split of the cores the process may use (as they were before share_haptic_core()), when
  // `wanted` and there are 2 or more.
  static CoreSplit make(bool wanted);
  bool pin_haptic() const;  // the calling thread onto the haptic core
  void pin_other() const;   // the calling thread onto the others
};

// The cores the process may use (see CoreSplit::make); false when they cannot be read.
bool allowed_cores(cpu_set_t& allowed);

}  // namespace fetouch::app
