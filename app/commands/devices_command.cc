// `fetouch devices`: the haptic devices this machine can drive (docs/devices.md). OpenHaptics does
// not enumerate devices: the default device and each --name given are opened in turn and described,
// or the one line that says why none is available. With --timing, how well this machine keeps the
// haptic thread's 1 kHz schedule instead (app/haptic_schedule.h).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/haptic_schedule.h"
#include "app/json_writer.h"
#include "haptics/phantom.h"

namespace fetouch::app {

namespace {

struct DevicesOptions {
  std::string library;
  std::vector<std::string> names;
  bool json = false;
  double timing_s = 0;  // > 0: the timing check, for this long
};

// The haptic thread's schedule with empty ticks: the floor under every session's tick lateness.
int run_timing(const DevicesOptions& o) {
  constexpr double kPeriod = 1e-3;  // the haptic rate (ARCHITECTURE.md)
  std::fprintf(stderr, "checking the haptic thread's 1 kHz schedule for %.1f s, with no work in its ticks...\n", o.timing_s);
  const TimingCheck t = check_haptic_timing(o.timing_s, kPeriod, /*pin_core=*/true, /*realtime_priority=*/true);
  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("duration_s").value(o.timing_s);
    json.key("period_s").value(kPeriod);
    json.key("ticks").value(t.ticks);
    json.key("realtime_priority").value(t.realtime_priority);
    json.key("core").value(t.core);
    json.key("lateness_p50_s").value(t.lateness_p50_s);
    json.key("lateness_p99_s").value(t.lateness_p99_s);
    json.key("lateness_max_s").value(t.lateness_max_s);
    json.key("later_than_100us").value(t.later_than_100us);
    json.key("later_than_1ms").value(t.later_than_1ms);
    json.key("overruns").value(t.overruns);
    json.key("restarts").value(t.restarts);
    json.end_object();
    std::cout << "\n";
  } else {
    const std::string core = t.core < 0 ? "not pinned" : "core " + std::to_string(t.core);
    std::printf("haptic schedule: %ld ticks at 1 kHz, %s, %s\n  tick lateness p50 %.1f us, p99 %.1f us, max %.3f ms\n"
                "  %ld ticks later than 0.1 ms, %ld later than 1 ms; %ld overran into the next period; the schedule "
                "started afresh %ld time%s\n",
                t.ticks, core.c_str(), t.realtime_priority ? "SCHED_FIFO" : "normal priority (SCHED_FIFO refused)",
                1e6 * t.lateness_p50_s, 1e6 * t.lateness_p99_s, 1e3 * t.lateness_max_s, t.later_than_100us,
                t.later_than_1ms, t.overruns, t.restarts, t.restarts == 1 ? "" : "s");
  }
  return kExitOk;
}

int run_devices(const DevicesOptions& o) {
  if (o.timing_s > 0) return run_timing(o);
  const std::string library = haptics::hd_library_path(o.library);
  std::vector<haptics::PhantomInfo> found;
  std::vector<std::string> problems;
  try {
    haptics::load_hd_library(library);
  } catch (const std::exception& e) {
    problems.push_back(e.what());
  }
  if (problems.empty()) {
    const std::vector<std::string> names = o.names.empty() ? std::vector<std::string>{""} : o.names;
    for (const std::string& name : names) {
      try {
        found.push_back(haptics::describe_phantom(library, name));
      } catch (const std::exception& e) {
        problems.push_back(e.what());
      }
    }
  }
  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("library").value(library);
    json.key("devices").begin_array();
    for (const auto& d : found) {
      json.begin_object();
      json.key("name").value(d.name);
      json.key("model").value(d.model);
      json.key("serial").value(d.serial);
      json.key("workspace_mm").values(std::vector<double>(d.workspace_mm, d.workspace_mm + 6));
      json.key("max_force_n").value(d.max_force_n);
      json.key("max_continuous_force_n").value(d.max_continuous_force_n);
      json.key("max_stiffness_n_per_mm").value(d.max_stiffness_n_per_mm);
      json.key("update_rate_hz").value(d.update_rate_hz);
      json.key("calibration").value(d.calibration);
      json.end_object();
    }
    json.end_array();
    json.key("problems").values(problems);
    json.end_object();
    std::cout << "\n";
  } else {
    for (const auto& d : found) {
      const double* w = d.workspace_mm;
      std::printf("%s: %s, serial %s\n  workspace %.0f x %.0f x %.0f mm; max force %.2f N, continuous %.2f N, "
                  "stiffness %.2f N/mm; %.0f Hz; calibration %s\n",
                  d.name.empty() ? "default device" : d.name.c_str(), d.model.c_str(), d.serial.c_str(), w[3] - w[0],
                  w[4] - w[1], w[5] - w[2], d.max_force_n, d.max_continuous_force_n, d.max_stiffness_n_per_mm,
                  d.update_rate_hz, d.calibration.c_str());
    }
    for (const auto& p : problems) std::cerr << "error: " << p << "\n";
  }
  return found.empty() ? kExitFailure : kExitOk;
}

}  // namespace

void add_devices_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<DevicesOptions>();
  CLI::App* cmd = parent.add_subcommand("devices", "List the haptic devices (PHANTOM) this machine can drive");
  cmd->add_option("--library", o->library, "OpenHaptics' libHD.so (default: $FETOUCH_LIBHD, else libHD.so)");
  cmd->add_option("--name", o->names, "A device name from the vendor's set-up tool (repeatable; default: the default device)");
  cmd->add_flag("--json", o->json, "Print as JSON");
  cmd->add_option("--timing", o->timing_s,
                  "Instead: run the haptic thread's 1 kHz schedule (its own core, SCHED_FIFO) this many seconds with "
                  "empty ticks, and report how late its ticks start: this machine's floor under any session's")
      ->check(CLI::Range(1e-3, 3600.0));
  cmd->callback([o, &exit_code] { exit_code = run_devices(*o); });
}

}  // namespace fetouch::app
