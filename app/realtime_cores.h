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

// The nice value a real-time session's solver thread asks for. The haptic thread has its core, but
// the solver shares the others with whatever else the machine runs: at the default nice 0 one busy
// program took half of the solver's core, and the trainer skipped 4-6 frames in a 30 s take (solve
// p99 68-70 ms; 12-16 and 108-119 ms with two); at -10 (CFS weight 9,548 against 1,024) the same
// loads left it 0 skipped, p99 38-46 ms (docs/trainer.md, "When the machine is busy"). Threads the
// solver starts inherit it.
inline constexpr int kSolverNice = -10;

// The nice value the trainer's window thread asks for (app/trainer/trainer_command.cc). The window
// shares the haptic thread's core, never the solver's, so it cannot slow the solver; against other
// programs it keeps the view moving. Under two busy loops the view rendered 7 times a second at 0,
// 10-12.5 at -5 (the ultrasound 6.5-6.8 and 9.5-11.9 images/s); at -10 it rendered 14 a second but
// starved its own imager (nice +5): 9-10 images/s.
inline constexpr int kWindowNice = -5;

// Raises the calling thread's priority to `nice` where the process may (root, CAP_SYS_NICE or
// RLIMIT_NICE; never lowers it) and returns the nice value the thread has afterwards. Threads it
// starts later inherit it.
int raise_thread_priority(int nice);
inline int raise_solver_priority() { return raise_thread_priority(kSolverNice); }
// The calling thread's nice value (0 where it cannot be read).
int thread_nice();

}  // namespace fetouch::app
