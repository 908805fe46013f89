// The stand-in libHD.so's simulated device (tests/devices/standin_hd.cc): its state, the hand model,
// the log and the servo thread. Tests only.
#pragma once

#include <algorithm>
#include <array>
#include <map>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <pthread.h>
#include <sched.h>
#include <time.h>

extern "C" {
typedef unsigned int HHD;
typedef unsigned int HDenum;
typedef unsigned int HDerror;
typedef unsigned int HDuint;
typedef unsigned int HDCallbackCode;
typedef int HDint;
typedef double HDdouble;
typedef unsigned short HDushort;
typedef unsigned long HDulong;
typedef unsigned long HDSchedulerHandle;
typedef unsigned char HDboolean;
typedef const char* HDstring;
typedef HDCallbackCode (*HDSchedulerCallback)(void*);
struct HDErrorInfo {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};
}

namespace standin {

constexpr HHD kInvalidHandle = 0xFFFFFFFF;
constexpr HDerror kSuccess = 0, kInvalidEnum = 0x100, kInvalidOperation = 0x102, kBadHandle = 0x104,
                  kExceededMaxForce = 0x201, kDeviceFault = 0x300, kCommError = 0x302, kCommConfigError = 0x303, kIllegalBegin = 0x400,
                  kIllegalEnd = 0x401;
constexpr HDenum kCurrentButtons = 0x2000, kCurrentPosition = 0x2050, kCurrentVelocity = 0x2051,
                 kCurrentTransform = 0x2052, kDeviceModelType = 0x2501, kDeviceSerialNumber = 0x2504,
                 kUsableWorkspaceDimensions = 0x2551, kUpdateRate = 0x2600, kNominalMaxStiffness = 0x2602,
                 kNominalMaxForce = 0x2603, kNominalMaxContinuousForce = 0x2604, kCurrentForce = 0x2700;
constexpr HDenum kCalibrationOk = 0x5000, kCalibrationNeedsManualInput = 0x5002;
constexpr double kPeriod = 1e-3;

inline std::string env(const char* name, const char* fallback = "") {
  const char* v = std::getenv(name);
  return v ? v : fallback;
}

inline std::vector<std::string> split(const std::string& text, char by) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, by);)
    if (!part.empty()) out.push_back(part);
  return out;
}

struct Row {
  double t;
  double x[3];
};

// The hand's targets every tick, read from a CSV (t, x, y, z), linear between rows.
inline std::vector<std::array<double, 3>> targets_from(const std::string& path) {
  std::vector<Row> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    Row r;
    if (std::sscanf(line.c_str(), "%lf , %lf , %lf , %lf", &r.t, &r.x[0], &r.x[1], &r.x[2]) == 4) rows.push_back(r);
  }
  std::vector<std::array<double, 3>> out;
  if (rows.empty()) return out;
  const double t0 = rows.front().t;
  std::size_t i = 0;
  for (long k = 0;; ++k) {
    const double t = t0 + k * kPeriod;
    if (t > rows.back().t + 1e-12) break;
    while (i + 1 < rows.size() && rows[i + 1].t <= t) ++i;
    std::array<double, 3> p;
    if (i + 1 >= rows.size()) {
      for (int d = 0; d < 3; ++d) p[d] = rows.back().x[d];
    } else {
      const double a = (t - rows[i].t) / (rows[i + 1].t - rows[i].t);
      for (int d = 0; d < 3; ++d) p[d] = (1 - a) * rows[i].x[d] + a * rows[i + 1].x[d];
    }
    out.push_back(p);
  }
  return out;
}

struct Logged {
  double t;
  double force[3], position_mm[3];
};

struct Device {
  std::string name;
  bool open = false, in_frame = false;
  std::vector<std::array<double, 3>> targets, target_velocities;
  double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  double force[3] = {0, 0, 0}, pending[3] = {0, 0, 0};
  long tick = 0;
  std::vector<Logged> log;
  long violations = 0;
};

struct Button {
  int bit;
  double from, to;
};

struct State {
  std::mutex mutex;  // the stand-in's own state (never held while a callback runs)
  std::vector<Device> devices;
  std::vector<HDErrorInfo> errors;
  HHD current = kInvalidHandle;
  std::vector<Button> buttons;
  double max_force = 3.3;
  double phi[2][2], gamma[2], stiffness = 300, damping = 8;
  std::string fault;
  double fault_at = 1.0;
  bool stalled = false;
  // The scheduler.
  std::vector<std::pair<HDSchedulerCallback, void*>> callbacks;
  std::thread servo;
  std::atomic<bool> running{false};
  std::atomic<long> servo_tick{0};  // ticks since the first asynchronous callback was scheduled
  bool session_started = false;
  std::atomic<bool> in_callbacks{false};
};

inline State& state() {
  static State* s = [] {
    auto* st = new State;
    const auto hand = split(env("FETOUCH_STANDIN_HAND", "0.3,300,8"), ',');
    const double m = std::stod(hand.at(0)), k = std::stod(hand.at(1)), b = std::stod(hand.at(2));
    st->stiffness = k, st->damping = b;
    // exp of [0 1 0; -k/m -b/m 1/m; 0 0 0] T by scaling and squaring a Taylor series.
    double a[3][3] = {{0, kPeriod, 0}, {-k / m * kPeriod, -b / m * kPeriod, kPeriod / m}, {0, 0, 0}};
    for (auto& row : a)
      for (double& x : row) x /= 1024;
    double e[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, term[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int n = 1; n <= 20; ++n) {
      double next[3][3] = {};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l < 3; ++l) next[i][j] += term[i][l] * a[l][j] / n;
      std::memcpy(term, next, sizeof term);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) e[i][j] += term[i][j];
    }
    for (int s = 0; s < 10; ++s) {
      double sq[3][3] = {};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l < 3; ++l) sq[i][j] += e[i][l] * e[l][j];
      std::memcpy(e, sq, sizeof e);
    }
    st->phi[0][0] = e[0][0], st->phi[0][1] = e[0][1], st->phi[1][0] = e[1][0], st->phi[1][1] = e[1][1];
    st->gamma[0] = e[0][2], st->gamma[1] = e[1][2];
    st->max_force = std::stod(env("FETOUCH_STANDIN_MAX_FORCE", "3.3"));
    st->fault = env("FETOUCH_STANDIN_FAULT");
    st->fault_at = std::stod(env("FETOUCH_STANDIN_FAULT_AT", "1.0"));
    for (const std::string& b : split(env("FETOUCH_STANDIN_BUTTONS"), ';')) {
      Button button{};
      if (std::sscanf(b.c_str(), "%d@%lf-%lf", &button.bit, &button.from, &button.to) == 3) st->buttons.push_back(button);
    }
    std::map<std::string, std::string> trajectories;
    const std::string t = env("FETOUCH_STANDIN_TRAJECTORY");
    for (const std::string& n : split(env("FETOUCH_STANDIN_DEVICES", "Default PHANToM"), ',')) {
      Device d;
      d.name = n;
      st->devices.push_back(d);
    }
    for (Device& d : st->devices) {
      std::string file = t.find('=') == std::string::npos ? t : std::string();
      for (const std::string& pair : split(t, ','))
        if (pair.rfind(d.name + "=", 0) == 0) file = pair.substr(d.name.size() + 1);
      if (file.empty()) continue;
      d.targets = targets_from(file);
      const std::size_t n = d.targets.size();
      d.target_velocities.assign(n, {0, 0, 0});
      for (std::size_t i = 0; i < n && n > 1; ++i) {
        const std::size_t lo = i == 0 ? 0 : i - 1, hi = i + 1 == n ? i : i + 1;
        for (int c = 0; c < 3; ++c) d.target_velocities[i][c] = (d.targets[hi][c] - d.targets[lo][c]) / (double(hi - lo) * kPeriod);
      }
      for (int c = 0; c < 3; ++c) d.x[c] = d.targets.empty() ? 0 : d.targets.front()[c];
    }
    return st;
  }();
  return *s;
}

inline void push_error(HDerror code, HHD device, int internal = 0) { state().errors.push_back({code, internal, device}); }

inline Device* device(HHD h) {
  State& s = state();
  return h < s.devices.size() && s.devices[h].open ? &s.devices[h] : nullptr;
}

inline double servo_time() { return double(state().servo_tick.load()) * kPeriod; }

// One servo tick of the hand: over the last tick, its target and the force it was sent, held.
inline void advance_hand(State& s, Device& d) {
  if (d.tick > 0) {
    // No trajectory: the target rests at the origin.
    const std::size_t k = d.targets.empty() ? 0 : std::min<std::size_t>(static_cast<std::size_t>(d.tick - 1), d.targets.size() - 1);
    for (int c = 0; c < 3; ++c) {
      const double f = std::isfinite(d.force[c]) ? d.force[c] : 0;
      const double target = d.targets.empty() ? 0 : d.targets[k][c], speed = d.targets.empty() ? 0 : d.target_velocities[k][c];
      const double u = s.stiffness * target + s.damping * speed + f;
      const double x = s.phi[0][0] * d.x[c] + s.phi[0][1] * d.v[c] + s.gamma[0] * u;
      const double v = s.phi[1][0] * d.x[c] + s.phi[1][1] * d.v[c] + s.gamma[1] * u;
      d.x[c] = x, d.v[c] = v;
    }
  }
  ++d.tick;
}

inline void write_log() {
  State& s = state();
  const std::string path = env("FETOUCH_STANDIN_LOG");
  if (path.empty()) return;
  std::ofstream out(path);
  out << "# stand-in libHD.so: every force sent; violations = forces not finite or above " << s.max_force << " N\n";
  out << "device,t_s,fx_n,fy_n,fz_n,x_mm,y_mm,z_mm\n";
  out.precision(17);
  long violations = 0;
  for (const Device& d : s.devices) {
    violations += d.violations;
    for (const Logged& l : d.log)
      out << d.name << "," << l.t << "," << l.force[0] << "," << l.force[1] << "," << l.force[2] << "," << l.position_mm[0]
          << "," << l.position_mm[1] << "," << l.position_mm[2] << "\n";
  }
  out << "# violations " << violations << "\n";
}

inline void servo_loop() {
  State& s = state();
  sched_param priority{};  // the vendor's servo thread runs at a real-time priority where it may
  priority.sched_priority = 80;
  pthread_setschedparam(pthread_self(), SCHED_FIFO, &priority);
  timespec deadline{};
  clock_gettime(CLOCK_MONOTONIC, &deadline);
  bool stall_done = false;
  while (s.running.load()) {
    deadline.tv_nsec += 1000000;
    if (deadline.tv_nsec >= 1000000000L) deadline.tv_nsec -= 1000000000L, ++deadline.tv_sec;
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0) {
    }
    if (s.fault == "stall" && !stall_done && servo_time() >= s.fault_at) {
      stall_done = true;  // the servo thread stalls for 300 ms, once
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      clock_gettime(CLOCK_MONOTONIC, &deadline);
    }
    std::vector<std::pair<HDSchedulerCallback, void*>> callbacks;
    {
      std::lock_guard<std::mutex> lock(s.mutex);
      // The hand sets off along its trajectory with the first asynchronous callback (the session).
      if (s.session_started)
        for (Device& d : s.devices)
          if (d.open) advance_hand(s, d);
      callbacks = s.callbacks;
    }
    std::vector<std::pair<HDSchedulerCallback, void*>> done;
    for (const auto& c : callbacks)
      if (c.first(c.second) != 1) done.push_back(c);
    if (!done.empty()) {
      std::lock_guard<std::mutex> lock(s.mutex);
      for (const auto& c : done) s.callbacks.erase(std::remove(s.callbacks.begin(), s.callbacks.end(), c), s.callbacks.end());
    }
    if (s.session_started) s.servo_tick.fetch_add(1);
  }
}

}  // namespace standin
