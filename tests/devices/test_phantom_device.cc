// The PHANTOM family (haptics/phantom.h) on the stand-in libHD.so, loaded through the same dlopen
// path as the vendor's library: what it says when the library or an entry point is missing, when
// the device cannot be opened or is uncalibrated; and, on the stand-in's own servo thread, that every
// force it is sent is finite and within the clamp, force errors switch the force off until they
// clear, and a device fault is reported once and the force stays off.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "haptics/phantom.h"
#include "tests/support/test_paths.h"

namespace fetouch::haptics {
namespace {

namespace fs = std::filesystem;

struct Logged {
  double t, f[3], x_mm[3];
};

// The stand-in's log: one row per force it was sent, and its count of forces that broke its limits.
std::vector<Logged> read_log(const fs::path& path, long& violations) {
  std::vector<Logged> rows;
  std::ifstream in(path);
  violations = -1;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# violations ", 0) == 0) violations = std::stol(line.substr(13));
    Logged l;
    char name[64];
    if (std::sscanf(line.c_str(), "%63[^,],%lf,%lf,%lf,%lf,%lf,%lf,%lf", name, &l.t, &l.f[0], &l.f[1], &l.f[2], &l.x_mm[0],
                    &l.x_mm[1], &l.x_mm[2]) == 8)
      rows.push_back(l);
  }
  return rows;
}

struct Context {
  PhantomDevice* device;
  Eigen::Vector3d request;
  long ticks = 0, limit = 0;
  std::vector<Eigen::Vector3d> positions, sent;
};

bool tick(void* c) noexcept {
  auto* x = static_cast<Context*>(c);
  x->positions[x->ticks] = x->device->read().position_m;
  x->sent[x->ticks] = x->device->write(x->request);
  return ++x->ticks < x->limit;
}

// Runs `ticks` servo ticks asking for `request`; the device closes (and the stand-in writes its log).
Context run(PhantomSettings settings, const Eigen::Vector3d& request, long ticks, const char* fault, long* recoverable,
            std::string* fault_text, const fs::path& log) {
  setenv("FETOUCH_STANDIN_LOG", log.c_str(), 1);
  setenv("FETOUCH_STANDIN_FAULT", fault, 1);
  setenv("FETOUCH_STANDIN_FAULT_AT", "0.1", 1);
  settings.library = STANDIN_LIBHD;
  PhantomDevice device(settings);
  Context c{&device, request, 0, ticks, std::vector<Eigen::Vector3d>(ticks), std::vector<Eigen::Vector3d>(ticks)};
  ServoClock* clock = device.servo_clock();
  EXPECT_NE(clock, nullptr);
  clock->start(&tick, &c);
  while (c.ticks < ticks) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  clock->stop();
  if (recoverable) *recoverable = device.recoverable_errors();
  if (fault_text) *fault_text = device.fault() ? device.fault() : "";
  return c;
}

TEST(PhantomLibrary, AMissingLibrarySaysWhichAndWhatToInstall) {
  try {
    load_hd_library("/nonexistent/libHD.so");
    FAIL();
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/nonexistent/libHD.so"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot open shared object file"), std::string::npos) << m;  // dlerror's text
    EXPECT_NE(m.find("FETOUCH_LIBHD"), std::string::npos) << m;
    EXPECT_NE(m.find("OpenHaptics"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST(PhantomLibrary, AMissingEntryPointIsNamed) {
  try {
    load_hd_library(STANDIN_BROKEN_LIBHD);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("has no hdEndFrame"), std::string::npos) << e.what();
  }
}

TEST(PhantomLibrary, TheLibraryComesFromTheSceneThenTheEnvironment) {
  setenv("FETOUCH_LIBHD", "/from/environment/libHD.so", 1);
  EXPECT_EQ(hd_library_path("/from/scene/libHD.so"), "/from/scene/libHD.so");
  EXPECT_EQ(hd_library_path(""), "/from/environment/libHD.so");
  unsetenv("FETOUCH_LIBHD");
  EXPECT_EQ(hd_library_path(""), "libHD.so");
}

// Faults at open: each refused with the HD error or the state named, and what to do.
TEST(PhantomDevice, InitFailuresAndAnUncalibratedDeviceAreRefusedSayingWhatToDo) {
  for (const auto& [fault, cause, remedy] : {std::tuple<const char*, const char*, const char*>{"init", "HD_COMM_ERROR (0x302", "dialout"},
                                             {"uncalibrated", "not calibrated", "inkwell"}}) {
    setenv("FETOUCH_STANDIN_FAULT", fault, 1);
    PhantomSettings s;
    s.library = STANDIN_LIBHD;
    try {
      PhantomDevice device(s);
      ADD_FAILURE() << fault;
    } catch (const std::runtime_error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(cause), std::string::npos) << m;
      EXPECT_NE(m.find(remedy), std::string::npos) << m;
    }
  }
  unsetenv("FETOUCH_STANDIN_FAULT");
}

TEST(PhantomDevice, ForcesReachTheDeviceClampedInItsUnits) {
  const fs::path log = fs::temp_directory_path() / ("standin_clamp_" + std::to_string(getpid()) + ".csv");
  setenv("FETOUCH_STANDIN_MAX_FORCE", "1.5", 1);  // the device's nominal continuous maximum
  PhantomSettings s;
  s.max_force_n = 2.0;  // the scene's, higher: the device's 1.5 N wins
  s.mapping.ramp_s = 0;
  const Context c = run(s, Eigen::Vector3d(0, 0, 3), 500, "", nullptr, nullptr, log);
  unsetenv("FETOUCH_STANDIN_MAX_FORCE");
  long violations = 0;
  const std::vector<Logged> rows = read_log(log, violations);
  ASSERT_GE(rows.size(), 500u);
  EXPECT_EQ(violations, 0);
  for (const Logged& l : rows) EXPECT_NEAR(l.f[2], 1.5, 1e-12);
  for (const auto& f : c.sent) EXPECT_NEAR(f.z(), 1.5, 1e-12);  // what the session would record
  // The hand (at rest at the origin, pulled back by its spring) is pushed up by 1.5 N: the
  // positions read are the stand-in's millimetres as metres.
  for (std::size_t k = 0; k < 400; ++k) EXPECT_NEAR(c.positions[k].z(), 1e-3 * rows[k].x_mm[2], 1e-12) << k;
  EXPECT_GT(c.positions.back().z(), 0.9 * 1.5 / 300);  // towards the spring's 1.5 / 300 m
  fs::remove(log);
}

// The stand-in's hand held at 2 cm along x by its trajectory; button 0 pressed at 0.1 s engages,
// button 1 held from 0.8 s to 0.9 s clutches while the hand moves on to 5 cm.
TEST(PhantomDevice, EngageRampsTheForceInAndTheClutchRecentres) {
  const fs::path dir = fs::temp_directory_path() / ("standin_clutch_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "hand.csv") << "t,x,y,z\n0,0.02,0,0\n0.75,0.02,0,0\n0.95,0.05,0,0\n2,0.05,0,0\n";
  setenv("FETOUCH_STANDIN_TRAJECTORY", (dir / "hand.csv").c_str(), 1);
  setenv("FETOUCH_STANDIN_BUTTONS", "0@0.1-0.15;1@0.8-0.9", 1);
  setenv("FETOUCH_STANDIN_HAND", "0.3,3000,60", 1);  // a stiff hand: it barely yields to 0.2 N
  PhantomSettings s;
  s.mapping.engage_button = 0;
  s.mapping.clutch_button = 1;
  const Context c = run(s, Eigen::Vector3d(0, 0.2, 0), 1200, "", nullptr, nullptr, dir / "log.csv");
  long violations = 0;
  const std::vector<Logged> rows = read_log(dir / "log.csv", violations);
  ASSERT_GE(rows.size(), 1200u);
  for (const Logged& l : rows) {
    const double t = l.t;
    // g = 0 before engage, (t - 0.1) / 0.5 over the ramp, 1 after, 0 while clutched, ramping again after.
    if (t < 0.099) {
      EXPECT_EQ(l.f[1], 0) << t;
    }
    if (t > 0.101 && t < 0.599) {
      EXPECT_NEAR(l.f[1], 0.2 * (t - 0.1) / 0.5, 0.2 * 0.003) << t;
    }
    if (t > 0.601 && t < 0.799) {
      EXPECT_NEAR(l.f[1], 0.2, 1e-12) << t;
    }
    if (t > 0.801 && t < 0.899) {
      EXPECT_EQ(l.f[1], 0) << t;
    }
    if (t > 0.901 && t < 1.399) {
      EXPECT_NEAR(l.f[1], 0.2 * (t - 0.9) / 0.5, 0.2 * 0.003) << t;
    }
  }
  // Positions: the probe stays where the clutch was pressed, then moves on from there as the hand
  // does: after the release the scene's x is the hand's less what the hand moved while clutched.
  const double at_press = c.positions[800].x();
  for (int k = 801; k < 900; ++k) EXPECT_EQ(c.positions[k].x(), at_press) << k;
  const double hand_at_release = 1e-3 * rows[900].x_mm[0];
  for (int k = 1000; k < 1200; ++k) EXPECT_NEAR(c.positions[k].x(), 1e-3 * rows[k].x_mm[0] - (hand_at_release - at_press), 1e-12) << k;
  EXPECT_GT(hand_at_release - at_press, 0.01);  // the hand moved on by over a centimetre meanwhile
  EXPECT_EQ(violations, 0);
  unsetenv("FETOUCH_STANDIN_TRAJECTORY");
  unsetenv("FETOUCH_STANDIN_BUTTONS");
  unsetenv("FETOUCH_STANDIN_HAND");
  fs::remove_all(dir);
}

TEST(PhantomDevice, ForceErrorsSwitchTheForceOffUntilTheyClear) {
  const fs::path log = fs::temp_directory_path() / ("standin_burst_" + std::to_string(getpid()) + ".csv");
  PhantomSettings s;
  s.mapping.ramp_s = 0.05;
  long recoverable = 0;
  std::string fault;
  const Context c = run(s, Eigen::Vector3d(0.5, 0, 0), 600, "force_burst", &recoverable, &fault, log);
  // The stand-in reports HD_EXCEEDED_MAX_FORCE on every frame from 0.1 s to 0.15 s: about 50.
  EXPECT_GE(recoverable, 45);
  EXPECT_LE(recoverable, 55);
  EXPECT_EQ(fault, "");
  long violations = 0;
  const std::vector<Logged> rows = read_log(log, violations);
  EXPECT_EQ(violations, 0);
  // Off from the first error until 100 ms after the last (0.15 s): zero from about 0.101 s to 0.25 s,
  // then ramping in over 50 ms, then 0.5 N again.
  for (const Logged& l : rows) {
    if (l.t > 0.102 && l.t < 0.248) {
      EXPECT_EQ(l.f[0], 0) << l.t;
    }
    if (l.t > 0.31 && l.t < 0.59) {
      EXPECT_NEAR(l.f[0], 0.5, 1e-12) << l.t;
    }
  }
  fs::remove(log);
}

TEST(PhantomDevice, ADeviceFaultIsReportedAndTheForceStaysOff) {
  const fs::path log = fs::temp_directory_path() / ("standin_fault_" + std::to_string(getpid()) + ".csv");
  PhantomSettings s;
  s.mapping.ramp_s = 0;
  std::string fault;
  run(s, Eigen::Vector3d(0.5, 0, 0), 300, "device_fault", nullptr, &fault, log);
  EXPECT_NE(fault.find("HD_DEVICE_FAULT (0x300"), std::string::npos) << fault;
  EXPECT_NE(fault.find("Device fault"), std::string::npos) << fault;  // the driver's own text
  long violations = 0;
  for (const Logged& l : read_log(log, violations))
    if (l.t > 0.102) {
      EXPECT_EQ(l.f[0], 0) << l.t;
    }
  EXPECT_EQ(violations, 0);
  fs::remove(log);
}

}  // namespace
}  // namespace fetouch::haptics
