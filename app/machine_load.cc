#include "app/machine_load.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

namespace fetouch::app {

namespace {

std::string read_all(const char* path) {
  std::ifstream in(path);
  return in ? std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()) : std::string();
}

}  // namespace

bool parse_proc_stat(const std::string& text, double& busy_ticks, double& all_ticks, int& cpus) {
  std::istringstream lines(text);
  std::string line;
  bool total = false;
  double busy = 0, all = 0;
  int count = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("cpu", 0) != 0) continue;
    std::istringstream fields(line);
    std::string name;
    fields >> name;
    if (name == "cpu") {
      // user nice system idle iowait irq softirq steal (guest time is inside user already).
      double v[8] = {};
      int read = 0;
      while (read < 8 && fields >> v[read]) ++read;
      if (read < 4) return false;  // older kernels stop after idle
      busy = v[0] + v[1] + v[2] + v[5] + v[6] + v[7];
      all = busy + v[3] + v[4];
      total = true;
    } else if (name.size() > 3 && std::all_of(name.begin() + 3, name.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      ++count;
    }
  }
  if (!total || count == 0 || !(all > 0)) return false;
  busy_ticks = busy, all_ticks = all, cpus = count;
  return true;
}

bool parse_own_stat(const std::string& text, double& own_ticks) {
  // pid (comm) state ppid ...: the command may hold spaces and parentheses, so the fields are
  // counted from the last ')'. utime and stime are fields 14 and 15, the 12th and 13th after it.
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return false;
  std::istringstream fields(text.substr(close + 1));
  std::vector<std::string> after;
  std::string field;
  while (after.size() < 13 && fields >> field) after.push_back(field);
  if (after.size() < 13) return false;
  try {
    own_ticks = std::stod(after[11]) + std::stod(after[12]);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

CpuSample sample_cpu() {
  CpuSample s;
  s.valid = parse_proc_stat(read_all("/proc/stat"), s.busy_ticks, s.all_ticks, s.cpus) &&
            parse_own_stat(read_all("/proc/self/stat"), s.own_ticks);
  return s;
}

double others_cores(const CpuSample& before, const CpuSample& after) {
  if (!before.valid || !after.valid || after.cpus <= 0) return 0;
  const double all = after.all_ticks - before.all_ticks;
  if (!(all > 0)) return 0;
  const double others = (after.busy_ticks - before.busy_ticks) - (after.own_ticks - before.own_ticks);
  return std::clamp(others / (all / after.cpus), 0.0, static_cast<double>(after.cpus));
}

}  // namespace fetouch::app
