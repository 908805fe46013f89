// `fetouch run SCENE`: an interactive real-time session without a window. The scene's devices
// (PHANTOMs, or replay and operator devices for a dry run), the 1 kHz tick on the device's servo
// callback where the device has one, a console status line, and Ctrl-C or SIGTERM to end it: the
// force ramps out over 0.2 s and the recording and summary are written. A device fault ends it the
// same way, with exit code 1 and the fault's name and text (docs/devices.md).
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include "app/build_info.h"
#include "app/commands/commands.h"
#include "app/error_text.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/mpi_session.h"
#include "app/output_guard.h"
#include "app/recording.h"
#include "app/scene_devices.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "app/session.h"
#include "fem/fem_environment.h"
#include "fem/tissue_model.h"
#include "haptics/phantom.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct RunOptions {
  std::string scene, out = "fetouch-run";
  double duration_s = 3600;
  bool json = false;
};

std::atomic<bool> g_stop{false};
extern "C" void request_stop(int) { g_stop.store(true); }

void write_run_summary(std::ostream& out, const config::Scene& scene, const SessionSummary& s, const fs::path& recording,
                       double seconds) {
  JsonWriter json(out);
  json.begin_object();
  json.key("program").value(std::string("fetouch ") + kVersion);
  json.key("command").value("run");
  json.key("scene").value(scene.source.string());
  json.key("recording").value(recording.string());
  json.key("ticks").value(s.ticks);
  json.key("frames").value(s.frames);
  json.key("seconds").value(seconds);
  json.key("stopped").value(s.stopped);
  json.key("fault").value(s.fault);
  json.key("fault_probe").value(s.fault_device >= 0 ? scene.probes[s.fault_device].name : std::string());
  json.key("recoverable_errors").values(s.recoverable_errors);
  json.key("max_force_n").value(s.max_force_n);
  json.key("solve_p50_s").value(s.solve_p50_s);
  json.key("solve_p99_s").value(s.solve_p99_s);
  json.key("solve_max_s").value(s.solve_max_s);
  json.key("min_stability_margin").value(s.min_stability_margin);
  const TimingSummary& t = s.timing;
  json.key("tick_period_p50_s").value(t.period_p50_s);
  json.key("tick_period_p99_s").value(t.period_p99_s);
  json.key("tick_period_max_s").value(t.period_max_s);
  json.key("tick_lateness_p99_s").value(t.lateness_p99_s);
  json.key("tick_lateness_max_s").value(t.lateness_max_s);
  json.key("late_ticks").value(t.tick_overruns);
  json.key("frame_overruns").value(t.frame_overruns);
  json.key("first_late_tick").value(t.first_late_tick);
  json.key("solver_differences").value(t.solver_differences);
  json.key("first_solver_difference_tick").value(t.first_solver_difference_tick);
  json.key("skipped_frames").value(t.skipped_frames);
  json.end_object();
  out << "\n";
}

int run_run(const RunOptions& o) {
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  config::Scene scene = std::move(*loaded);
  if (scene.probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes\n";
    return kExitBadInput;
  }
  try {
    std::vector<NamedInput> inputs = {{o.scene, "the scene"}, {scene.mesh.path, "the scene's mesh"}};
    for (const config::Probe& probe : scene.probes)
      inputs.emplace_back(probe.device.trajectory, "the trajectory of probe " + probe.name);
    const auto writes = [](const std::string& file) {
      return file == "recording.h5" || file == partial_path("recording.h5") || file == "summary.json";
    };
    refuse_overwriting({fs::path(o.out)}, inputs, fs::path(o.out), writes);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  ensure_mpi();
  const fs::path out(o.out), recording = out / "recording.h5";
  SessionSummary summary;
  double seconds = 0;
  try {
    scene.mesh = mesh_scene_volume(scene);
    const haptics::HapticLoopSettings settings = loop_settings(scene);
    // The devices first: a PHANTOM that cannot be had is said before the tissue is built.
    std::vector<std::unique_ptr<haptics::Device>> devices;
    std::vector<Eigen::Vector3d> starts;
    for (int p = 0; p < static_cast<int>(scene.probes.size()); ++p) {
      const config::Probe& probe = scene.probes[p];
      std::optional<haptics::Trajectory> path;
      if (probe.device.type == config::DeviceType::replay || probe.device.type == config::DeviceType::operator_model)
        path = read_probe_trajectory(probe.device.trajectory, probe.name, p);
      devices.push_back(make_device(probe, scene, settings, path ? &*path : nullptr));
      // Where its contact patch starts: a trajectory's first point, or where the device is now.
      if (path)
        starts.push_back(path->positions_m.front());
      else if (auto* phantom = dynamic_cast<haptics::PhantomDevice*>(devices.back().get()))
        starts.push_back(phantom->position_now());
      else
        starts.emplace_back(probe.device.offset_m[0], probe.device.offset_m[1], probe.device.offset_m[2]);
    }
    std::unique_ptr<fem::TissueModel> model = build_session_tissue(scene);
    SessionSettings session;
    session.loop = settings;
    for (int p = 0; p < static_cast<int>(scene.probes.size()); ++p) {
      const dealii::Point<3> touch = model->solver->boundary_point_nearest(dealii::Point<3>(starts[p][0], starts[p][1], starts[p][2]));
      model->solver->add_contact_patch(touch, scene.probes[p].radius_m);
      session.probes.push_back(scene.probes[p].name);
    }
    fem::FemEnvironment environment(std::move(model->solver), model->newton);
    environment.solver().set_assembly_threads(realtime_solver_cores(session) >= 2 ? 2 : 1);
    environment.solver().set_deterministic_factorisations(false);
    fs::create_directories(out);
    session.recording = recording;
    session.header.program_version = std::string("fetouch ") + kVersion + " (" + kGitRevision + ")";
    session.header.scene_path = scene.source.string();
    session.header.scene_text = scene.text;
    session.header.local_model = config::to_string(scene.haptics.local_model);
    session.header.hold = config::to_string(scene.haptics.hold);
    session.max_ticks = std::max<long>(1, std::lround(o.duration_s * scene.haptics.rate_hz));
    SessionMonitor monitor;
    session.monitor = &monitor;
    session.stop = &g_stop;
    // The status line, from the solver thread after a frame, at most twice a second (over itself on
    // a terminal, a line every 5 s otherwise).
    const bool terminal = isatty(STDERR_FILENO) != 0;
    auto last_status = std::chrono::steady_clock::now(), started = last_status;
    long last_ticks = 0, last_frame = 0;
    const int m = static_cast<int>(scene.probes.size());
    session.after_frame = [&](const FrameRecord& f) {
      const auto now = std::chrono::steady_clock::now();
      if (log::level() < log::Level::info || now - last_status < std::chrono::milliseconds(terminal ? 500 : 5000)) return;
      last_status = now;
      // The rates achieved since the last line: ticks and frames per second of wall time.
      const double wall = std::chrono::duration<double>(now - started).count();
      const long ticks_now = monitor.ticks.load();
      const double haptic_hz = wall > 0 ? double(ticks_now - last_ticks) / wall : 0;
      const double solver_hz = wall > 0 ? double(f.frame - last_frame) / wall : 0;
      started = now, last_ticks = ticks_now, last_frame = f.frame;
      std::ostringstream line;
      line.precision(3);
      line << std::fixed << "t " << f.time_s << " s  forces";
      for (int d = 0; d < m && d < SessionMonitor::kMaxDevices; ++d) line << " " << monitor.force_n[d].load() << " N";
      line.precision(0);
      line << "  haptic " << haptic_hz << " Hz  solver " << solver_hz << " Hz";
      line.precision(1);
      line << "  solve " << 1e3 * f.solve_s << " ms";
      line.precision(3);
      line << "  margin " << f.stability_margin << "  late ticks " << monitor.late_ticks.load();
      std::fprintf(stderr, terminal ? "\r%s   " : "%s\n", line.str().c_str());
    };
    // Installed last: MPI and PETSc install their own handlers when they start.
    g_stop = false;
    std::signal(SIGINT, request_stop);
    std::signal(SIGTERM, request_stop);
    log::info() << "running " << scene.probes.size() << " probe(s) in real time for at most " << o.duration_s
                << " s; Ctrl-C ends the session";
    const auto start = std::chrono::steady_clock::now();
    summary = run_realtime(environment, devices, session);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    if (terminal && log::level() >= log::Level::info) std::fprintf(stderr, "\n");
  } catch (const std::exception& e) {
    std::cerr << "error: " << naming(o.scene, e.what()) << "\n";
    return kExitFailure;
  }
  std::ostringstream text;
  write_run_summary(text, scene, summary, recording, seconds);
  try {
    write_text_file(out / "summary.json", text.str());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  if (o.json) std::cout << text.str();
  const TimingSummary& t = summary.timing;
  if (!o.json)
    std::printf("%ld ticks in %.1f s%s; tick period p50 %.3f ms, p99 %.3f ms, max %.3f ms; %ld late ticks; "
                "max force %.3f N; wrote %s\n",
                summary.ticks, seconds, summary.stopped ? " (stopped)" : "", 1e3 * t.period_p50_s, 1e3 * t.period_p99_s,
                1e3 * t.period_max_s, t.tick_overruns, summary.max_force_n, recording.string().c_str());
  for (std::size_t d = 0; d < summary.recoverable_errors.size(); ++d)
    if (summary.recoverable_errors[d] > 0)
      std::cerr << "warning: probe " << scene.probes[d].name << ": " << summary.recoverable_errors[d]
                << " force errors (the force was off until each cleared)\n";
  if (!summary.fault.empty()) {
    std::cerr << "error: probe " << scene.probes[summary.fault_device].name << ": the device failed: " << summary.fault
              << "; the session ended (force off, recording " << recording.string() << " closed)\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void add_run_command(CLI::App& parent, int& exit_code) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = parent.add_subcommand("run", "An interactive real-time session with the scene's devices (PHANTOM)");
  cmd->add_option("scene", options->scene, "The scene (YAML)")->required();
  cmd->add_option("--out", options->out, "Folder for recording.h5 and summary.json")->capture_default_str();
  cmd->add_option("--duration", options->duration_s, "Seconds at most (Ctrl-C ends it sooner)")
      ->check(CLI::Range(0.001, 3600.0))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the summary as JSON");
  cmd->callback([options, &exit_code] { exit_code = run_run(*options); });
}

}  // namespace fetouch::app
