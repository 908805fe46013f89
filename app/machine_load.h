// How much of the machine other programs take (Linux /proc): the trainer says so on its status line
// when the view slows down because of them, not because of the tissue (docs/trainer.md, "When the
// machine is busy").
//
// A sample holds the machine's CPU time since boot, busy and in all (/proc/stat's first line, in
// clock ticks: busy = user + nice + system + irq + softirq + steal, all = busy + idle + iowait), its
// number of CPUs (the cpuN lines), and this process's own CPU time (utime + stime of /proc/self/stat:
// every thread's, not its children's). Between two samples, other programs used
// (d busy - d own) / (d all / CPUs) cores: 1.0 is one core kept busy the whole time.
#pragma once

#include <string>

namespace fetouch::app {

struct CpuSample {
  double busy_ticks = 0, all_ticks = 0, own_ticks = 0;
  int cpus = 0;
  bool valid = false;  // both files read and understood
};

// The sample now (valid = false where /proc cannot be read: not Linux, a sandbox).
CpuSample sample_cpu();

// Parsers of the two files' text (false: not understood; the outputs are then unchanged).
bool parse_proc_stat(const std::string& text, double& busy_ticks, double& all_ticks, int& cpus);
bool parse_own_stat(const std::string& text, double& own_ticks);

// Cores other programs kept busy between two samples, 0 to `cpus` (0 when either is invalid or no
// time passed).
double others_cores(const CpuSample& before, const CpuSample& after);

}  // namespace fetouch::app
