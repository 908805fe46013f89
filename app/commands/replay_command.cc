// `fetouch replay`: a scene's probes moved by their devices without hardware (replay of a
// trajectory, or the virtual operator pulled along it), rendered by the 1 kHz loop against the FEM
// tissue in lockstep (app/session.h), recorded to HDF5 with a summary.
#include <CLI/CLI.hpp>
#include <mpi.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>
#include <memory>
#include <sstream>

#include "app/build_info.h"
#include "app/commands/commands.h"
#include "app/commands/hand_summary.h"
#include "app/error_text.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/mpi_session.h"
#include "app/output_guard.h"
#include "app/pvd.h"
#include "app/recording.h"
#include "app/scene_devices.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "app/session.h"
#include "fem/fem_environment.h"
#include "fem/physical_problem.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct ReplayOptions {
  std::string scene, trajectory, clock = "lockstep", out = "fetouch-replay";
  int mesh_every = 10;  // frames between deformed meshes (0: none)
  bool compare_ideal = false;
  bool json = false;
};

// Under MPI every rank steps the solver together (ARCHITECTURE.md section 5): rank 0 runs the
// session (haptic and I/O threads, recording) against this environment, which broadcasts each
// request to the other ranks before taking its own part in the collective solve; the other ranks
// serve() the same requests until rank 0 stops them. Deformed meshes are written by all ranks
// together (a piece per rank, gathered by a PVTU).
class DistributedEnvironment final : public haptics::Environment {
 public:
  DistributedEnvironment(fem::FemEnvironment& inner, int contacts) : inner_(inner), contacts_(contacts) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  }
  // Rank 0: stops the other ranks (also when the session ended in an exception).
  ~DistributedEnvironment() override {
    if (rank_ == 0 && !stopped_) command(kStop, 0);
  }
  int contacts() const override { return contacts_; }
  void initial(haptics::EnvironmentUpdate& out) override {
    command(kInitial, 0);
    inner_.initial(out);
  }
  void solve(const std::vector<haptics::ContactSample>& samples, long frame, haptics::EnvironmentUpdate& out) override {
    command(kSolve, frame);
    pack(samples);
    MPI_Bcast(buffer_.data(), static_cast<int>(buffer_.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
    inner_.solve(samples, frame, out);
  }
  // Rank 0: every rank writes its piece; returns the PVTU's file name.
  std::string write_mesh(const std::string& directory, const std::string& name, long counter) {
    command(kMesh, counter);
    return inner_.solver().write_vtu_pieces(directory, name, static_cast<unsigned int>(counter));
  }
  void stop() {
    command(kStop, 0);
    stopped_ = true;
  }
  // The other ranks: the requests of rank 0, until it stops.
  void serve(const std::string& directory, const std::string& name) {
    haptics::EnvironmentUpdate out;
    std::vector<haptics::ContactSample> samples(static_cast<std::size_t>(contacts_));
    for (;;) {
      long message[2];
      MPI_Bcast(message, 2, MPI_LONG, 0, MPI_COMM_WORLD);
      if (message[0] == kStop) return;
      if (message[0] == kInitial) inner_.initial(out);
      if (message[0] == kMesh) inner_.solver().write_vtu_pieces(directory, name, static_cast<unsigned int>(message[1]));
      if (message[0] == kSolve) {
        buffer_.resize(8 * samples.size());
        MPI_Bcast(buffer_.data(), static_cast<int>(buffer_.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
        unpack(samples);
        inner_.solve(samples, message[1], out);
      }
    }
  }

 private:
  enum : long { kStop = 0, kInitial = 1, kSolve = 2, kMesh = 3 };
  void command(long what, long argument) {
    long message[2] = {what, argument};
    MPI_Bcast(message, 2, MPI_LONG, 0, MPI_COMM_WORLD);
  }
  void pack(const std::vector<haptics::ContactSample>& samples) {
    buffer_.clear();
    for (const auto& s : samples) {
      buffer_.insert(buffer_.end(), {s.position.x(), s.position.y(), s.position.z(), s.force.x(), s.force.y(), s.force.z(),
                                     s.normal_force, s.in_contact ? 1.0 : 0.0});
    }
  }
  void unpack(std::vector<haptics::ContactSample>& samples) const {
    for (std::size_t c = 0; c < samples.size(); ++c) {
      const double* b = buffer_.data() + 8 * c;
      samples[c].position = {b[0], b[1], b[2]};
      samples[c].force = {b[3], b[4], b[5]};
      samples[c].normal_force = b[6];
      samples[c].in_contact = b[7] != 0;
    }
  }

  fem::FemEnvironment& inner_;
  int contacts_, rank_ = 0;
  bool stopped_ = false;
  std::vector<double> buffer_;
};

SessionSummary run_session(const config::Scene& scene, const ReplayOptions& o, const haptics::HapticLoopSettings& settings,
                           const fs::path* out, bool keep_forces, std::vector<Eigen::Vector3d>* patches = nullptr);

// The multirate local models against the ideal reference: the same session with the solver at
// the haptic rate (N = 1). Per local model and hold, per probe: the RMS of the force error
// relative to the ideal force's RMS, the peak error, and the 2 % settling time of the force after
// the trajectory's longest hold begins (the step it answers), against the force at the hold's end.
struct PairError {
  std::string model, hold;
  std::vector<double> rms_relative, peak_n, settling_s;
};
struct IdealComparison {
  std::vector<double> ideal_settling_s;
  std::vector<PairError> pairs;
  double hold_start_s = 0, hold_end_s = 0;
};

double settling_time(const std::vector<Eigen::Vector3d>& force, double period, double start, double end) {
  const long a = std::lround(start / period), b = std::min<long>(std::lround(end / period), static_cast<long>(force.size()) - 1);
  if (b <= a) return 0;
  const Eigen::Vector3d final_value = force[static_cast<std::size_t>(b)];
  const double band = 0.02 * final_value.norm();
  long last_out = a;
  for (long k = a; k <= b; ++k)
    if ((force[static_cast<std::size_t>(k)] - final_value).norm() > band) last_out = k;
  return (last_out - a) * period;
}

IdealComparison compare_with_ideal(const config::Scene& scene, const ReplayOptions& o) {
  IdealComparison c;
  const haptics::HapticLoopSettings base = loop_settings(scene);
  const auto hold = probe_trajectory(scene.probes.front(), 0, o.trajectory).longest_hold();
  c.hold_start_s = hold.first, c.hold_end_s = hold.second;
  haptics::HapticLoopSettings ideal_settings = base;
  ideal_settings.ratio = 1;
  ideal_settings.hold = haptics::HoldKind::zoh;
  log::info() << "the ideal reference: the solver at the haptic rate (N = 1)";
  const SessionSummary ideal = run_session(scene, o, ideal_settings, nullptr, true);
  const std::size_t probes = ideal.forces.size();
  for (std::size_t p = 0; p < probes; ++p)
    c.ideal_settling_s.push_back(settling_time(ideal.forces[p], base.period_s, hold.first, hold.second));
  for (auto model : {haptics::LocalModelKind::p, haptics::LocalModelKind::pi, haptics::LocalModelKind::smith,
                     haptics::LocalModelKind::pi_smith})
    for (auto h : {haptics::HoldKind::zoh, haptics::HoldKind::foh}) {
      haptics::HapticLoopSettings s = base;
      s.local_model = model, s.hold = h;
      const SessionSummary run = run_session(scene, o, s, nullptr, true);
      PairError e;
      e.model = haptics::to_string(model), e.hold = haptics::to_string(h);
      for (std::size_t p = 0; p < probes; ++p) {
        double error2 = 0, ideal2 = 0, peak = 0;
        const std::size_t n = std::min(run.forces[p].size(), ideal.forces[p].size());
        for (std::size_t k = 0; k < n; ++k) {
          const double d = (run.forces[p][k] - ideal.forces[p][k]).norm();
          error2 += d * d, ideal2 += ideal.forces[p][k].squaredNorm(), peak = std::max(peak, d);
        }
        e.rms_relative.push_back(ideal2 > 0 ? std::sqrt(error2 / ideal2) : 0);
        e.peak_n.push_back(peak);
        e.settling_s.push_back(settling_time(run.forces[p], base.period_s, hold.first, hold.second));
      }
      c.pairs.push_back(e);
    }
  return c;
}

void write_summary(std::ostream& out, const ReplayOptions& o, const config::Scene& scene, const SessionSummary& s,
                   const std::vector<Eigen::Vector3d>& patches, const fs::path& recording, double session_seconds,
                   double seconds, const std::optional<IdealComparison>& comparison) {
  JsonWriter json(out);
  json.begin_object();
  json.key("scene").value(scene.name);
  json.key("clock").value(o.clock);
  json.key("recording").value(recording.string());
  json.key("probes").begin_array();
  for (std::size_t p = 0; p < patches.size(); ++p) {
    json.begin_object();
    json.key("name").value(scene.probes[p].name);
    json.key("patch_m").begin_array().value(patches[p].x()).value(patches[p].y()).value(patches[p].z()).end_array();
    json.end_object();
  }
  json.end_array();
  json.key("ticks").value(s.ticks);
  json.key("frames").value(s.frames);
  const auto spread = [&json](const char* name, double p50, double p99, double max) {
    json.key(name).begin_object().key("p50").value(p50).key("p99").value(p99).key("max").value(max).end_object();
  };
  spread("solve_s", s.solve_p50_s, s.solve_p99_s, s.solve_max_s);
  // Lockstep: the solver always finishes within its frame, and the clock is simulated.
  json.key("overruns").value(s.timing.frame_overruns);
  if (o.clock == "realtime") {
    const TimingSummary& t = s.timing;
    spread("tick_period_s", t.period_p50_s, t.period_p99_s, t.period_max_s);
    spread("tick_lateness_s", t.lateness_p50_s, t.lateness_p99_s, t.lateness_max_s);
    json.key("first_late_tick").value(t.first_late_tick);
    json.key("solver_differences").value(t.solver_differences);
    json.key("first_solver_difference_tick").value(t.first_solver_difference_tick);
    json.key("tick_overruns").value(t.tick_overruns);
    json.key("skipped_frames").value(t.skipped_frames);
    json.key("dropped_samples").value(t.dropped_samples);
    json.key("realtime_priority").value(t.realtime_priority);
    json.key("solver_nice").value(static_cast<long>(t.solver_nice));
    json.key("haptic_core").value(static_cast<long>(t.haptic_core));
  }
  json.key("newton_failures").value(s.newton_failures);
  json.key("first_failure").value(s.first_failure);
  json.key("max_force_n").value(s.max_force_n);
  json.key("min_stability_margin").value(s.min_stability_margin);
  json.key("frames_with_unstable_gains").value(s.frames_with_unstable_gains);
  write_hand_json(json, scene, s);
  json.key("session_wall_s").value(session_seconds);
  json.key("wall_s").value(seconds);
  if (comparison) {
    json.key("compare_ideal").begin_object();
    json.key("hold_s").begin_array().value(comparison->hold_start_s).value(comparison->hold_end_s).end_array();
    json.key("ideal_settling_s").values(comparison->ideal_settling_s);
    json.key("pairs").begin_array();
    for (const auto& e : comparison->pairs) {
      json.begin_object();
      json.key("local_model").value(e.model);
      json.key("hold").value(e.hold);
      json.key("rms_error_relative").values(e.rms_relative);
      json.key("peak_error_n").values(e.peak_n);
      json.key("settling_s").values(e.settling_s);
      json.end_object();
    }
    json.end_array();
    json.end_object();
  }
  json.end_object();
  out << "\n";
}

// One session of the scene with these loop settings: the tissue built afresh, the devices from the
// scene. With `out`, the recording, the meshes and the PVD are written there.
SessionSummary run_session(const config::Scene& scene, const ReplayOptions& o, const haptics::HapticLoopSettings& settings,
                           const fs::path* out, bool keep_forces, std::vector<Eigen::Vector3d>* patches) {
  SceneRig rig = build_scene_rig(scene, settings, o.trajectory);
  if (patches) *patches = rig.patches;
  std::vector<std::unique_ptr<haptics::Device>>& devices = rig.devices;
  SessionSettings session;
  session.loop = settings;
  session.keep_forces = keep_forces;
  session.probes = rig.probes;
  // The main session shows its frames and expected end (not the comparison runs, nor under -q).
  session.progress = out && log::enabled(log::Level::info);
  fem::FemEnvironment& environment = *rig.environment;
  // Under MPI, rank 0 runs the session; the other ranks serve its solves until it is over.
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::optional<DistributedEnvironment> distributed;
  if (environment.solver().ranks() > 1) distributed.emplace(environment, static_cast<int>(scene.probes.size()));
  haptics::Environment& tissue = distributed ? static_cast<haptics::Environment&>(*distributed) : environment;
  const std::string mesh_dir = out ? (*out / "mesh").string() : std::string();
  if (distributed && rank != 0) {
    distributed->serve(mesh_dir, scene.name);
    return SessionSummary{};
  }
  std::vector<std::pair<double, std::string>> meshes;
  if (out) {
    fs::create_directories(*out);
    session.recording = *out / "recording.h5";
    session.header.program_version = std::string("fetouch ") + kVersion + " (" + kGitRevision + ")";
    session.header.scene_path = scene.source.string();
    session.header.scene_text = scene.text;
    session.header.local_model = config::to_string(scene.haptics.local_model);
    session.header.hold = config::to_string(scene.haptics.hold);
    // The deformed tissue every mesh_every frames (and at rest), as VTU files listed in a PVD (in
    // parallel: a piece per rank, gathered by a PVTU).
    const auto write_mesh = [&environment, &distributed, &meshes, &scene, &mesh_dir, out](long frame, double time_s) {
      if (distributed) {
        const std::string pvtu = distributed->write_mesh(mesh_dir, scene.name, frame);
        meshes.emplace_back(time_s, "mesh/" + fs::path(pvtu).filename().string());
        return;
      }
      const std::string name = "mesh/" + scene.name + "_" + std::to_string(frame) + ".vtu";
      environment.solver().write_vtu((*out / name).string());
      meshes.emplace_back(time_s, name);
    };
    if (o.mesh_every > 0) {
      fs::create_directories(mesh_dir);
      write_mesh(0, 0);
    }
    session.after_frame = [write_mesh, every = o.mesh_every](const FrameRecord& f) {
      log::debug() << "frame " << f.frame << " answered at " << f.time_s << " s: " << 1e3 * f.solve_s << " ms, "
                   << f.newton_iterations << " Newton iterations" << (f.converged ? "" : ", not converged");
      if (every > 0 && (f.frame + 1) % every == 0) write_mesh(f.frame + 1, f.time_s);
    };
  }
  const bool realtime = out && o.clock == "realtime";  // the comparison runs are lockstep
  if (realtime && !distributed) {
    // On one core a second assembly thread only takes turns with the first; and a frame never
    // waits for the factorisation worker: it takes the new factorisation up when it is ready.
    environment.solver().set_assembly_threads(realtime_solver_cores(session) >= 2 ? 2 : 1);
    environment.solver().set_deterministic_factorisations(false);
  }
  log::info() << "replaying " << scene.probes.size() << " probe(s) " << (realtime ? "in real time" : "in lockstep")
              << ", N = " << settings.ratio << ", " << haptics::to_string(settings.local_model) << " with " << haptics::to_string(settings.hold)
              << (distributed ? ", the solver on " + std::to_string(environment.solver().ranks()) + " MPI ranks" : "");
  SessionSummary summary = realtime ? run_realtime(tissue, devices, session) : run_lockstep(tissue, devices, session);
  if (distributed) distributed->stop();
  if (!meshes.empty()) write_pvd(*out / (scene.name + ".pvd"), meshes);
  return summary;
}

int run_replay(const ReplayOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  config::Scene scene = std::move(*loaded);
  if (scene.probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes to replay\n";
    return kExitBadInput;
  }
  try {  // before anything runs: the output must not replace the scene, its mesh or a trajectory
    std::vector<NamedInput> inputs = {{o.scene, "the scene"}, {scene.mesh.path, "the scene's mesh"},
                                      {o.trajectory, "the trajectory"}};
    for (const config::Probe& probe : scene.probes)
      inputs.emplace_back(probe.device.trajectory, "the trajectory of probe " + probe.name);
    // What a replay writes there (its meshes go to the mesh/ subfolder).
    const auto writes = [&scene](const std::string& file) {
      return file == "recording.h5" || file == partial_path("recording.h5") || file == "summary.json" ||
             file == scene.name + ".pvd";
    };
    refuse_overwriting({fs::path(o.out)}, inputs, fs::path(o.out), writes);
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  ensure_mpi();
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (rank != 0) log::set_level(log::Level::error);  // rank 0 speaks for all
  const fs::path out(o.out), recording = fs::path(o.out) / "recording.h5";
  SessionSummary summary;
  std::vector<Eigen::Vector3d> patches;  // each probe's contact patch centre
  std::optional<IdealComparison> comparison;
  double session_seconds = 0;  // the session itself (tissue built, replayed, written)
  try {
    scene.mesh = mesh_scene_volume(scene);
    const auto session_start = std::chrono::steady_clock::now();
    summary = run_session(scene, o, loop_settings(scene), &out, false, &patches);
    session_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - session_start).count();
    if (o.compare_ideal) comparison = compare_with_ideal(scene, o);
  } catch (const fem::PhysicalProblem& e) {  // a valid scene whose physics cannot do it: the work failed
    std::cerr << "error: the work failed: " << naming(o.scene, e.what() + physical_advice(scene)) << "\n";
    if (ranks > 1) MPI_Abort(MPI_COMM_WORLD, kExitFailure);
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "error: " << naming(o.scene, e.what()) << "\n";
    // The other ranks may be waiting in a collective call that will never come.
    if (ranks > 1) MPI_Abort(MPI_COMM_WORLD, kExitBadInput);
    return kExitBadInput;
  }
  if (rank != 0) return kExitOk;
  // Not an error (a probe may hover), but never silent: a replay that felt nothing says so.
  if (summary.max_force_n == 0)
    log::warning() << o.scene << ": no probe touched the tissue (the largest force was 0 N): each trajectory stays "
                   << "outside the tissue's deformed surface (check its start and depth against the mesh, or the sag under gravity)";
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ostringstream text;
  write_summary(text, o, scene, summary, patches, recording, session_seconds, seconds, comparison);
  try {
    write_text_file(out / "summary.json", text.str());
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  if (o.json) {
    std::cout << text.str();
  } else {
    std::printf("%ld ticks (%.2f s simulated), %ld frames in %.1f s; solve p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
                summary.ticks, summary.ticks / scene.haptics.rate_hz,
                summary.frames, session_seconds, 1e3 * summary.solve_p50_s, 1e3 * summary.solve_p99_s, 1e3 * summary.solve_max_s);
    const config::Haptics::DesignHand& hand = scene.haptics.design_hand;
    char with_hand[120] = " (the device held still)";
    if (hand.enabled)
      std::snprintf(with_hand, sizeof with_hand, " (with the design hand: %.3g kg, %.4g N/m, %.3g N s/m)", hand.mass_kg,
                    hand.stiffness_n_per_m, hand.damping_n_s_per_m);
    std::printf("  max force %.3f N, smallest stability margin %.3f%s, %ld Newton failures%s\n", summary.max_force_n,
                summary.min_stability_margin, with_hand, summary.newton_failures,
                summary.first_failure.empty() ? "" : (" (the first " + summary.first_failure + "; each rolled back, the last good answer held)").c_str());
    if (o.clock == "realtime") {
      const TimingSummary& t = summary.timing;
      const std::string core = t.haptic_core >= 0 ? ", haptic thread alone on core " + std::to_string(t.haptic_core) : "";
      const std::string solver = ", solver at nice " + std::to_string(t.solver_nice);
      std::printf("  real time%s%s%s: tick period p50 %.3f ms, p99 %.3f ms, max %.3f ms; lateness p99 %.1f us, max %.1f us; "
                  "%ld late ticks; %ld frame overruns, %ld frames skipped, %ld solved unlike lockstep\n",
                  t.realtime_priority ? " (SCHED_FIFO)" : " (normal priority)", core.c_str(), solver.c_str(), 1e3 * t.period_p50_s,
                  1e3 * t.period_p99_s, 1e3 * t.period_max_s, 1e6 * t.lateness_p99_s, 1e6 * t.lateness_max_s,
                  t.tick_overruns, t.frame_overruns, t.skipped_frames, t.solver_differences);
    }
    print_hand_summary(scene, summary);
    std::printf("  wrote %s, %s", recording.string().c_str(), (out / "summary.json").string().c_str());
    if (o.mesh_every > 0) std::printf(" and %s (open in ParaView)", (out / (scene.name + ".pvd")).string().c_str());
    std::printf("\n");
    if (comparison) {
      std::printf("against the ideal (N = 1; force settles 2 %% in %.3f s after the hold starts at %.2f s):\n",
                  comparison->ideal_settling_s.empty() ? 0.0 : comparison->ideal_settling_s[0], comparison->hold_start_s);
      std::printf("  %-9s %-5s %12s %12s %12s   (first probe)\n", "model", "hold", "RMS error", "peak (N)", "settling (s)");
      for (const auto& e : comparison->pairs)
        std::printf("  %-9s %-5s %11.2f%% %12.4f %12.3f\n", e.model.c_str(), e.hold.c_str(), 100 * e.rms_relative[0],
                    e.peak_n[0], e.settling_s[0]);
    }
  }
  return kExitOk;
}

}  // namespace

void add_replay_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = parent.add_subcommand("replay", "Replay a scene's probe trajectories against the tissue, headless");
  cmd->footer(
      "Moves each probe with its device (replay: the trajectory as recorded; operator: a hand model\n"
      "pulled along it), renders the force at the haptic rate through the scene's local model and\n"
      "hold, and solves the tissue once per frame: in lockstep (simulated time: the same inputs give\n"
      "the same forces, bit for bit) or in real time (--clock realtime). Writes DIR/recording.h5 (HDF5: per-tick device series,\n"
      "per-frame solver figures), DIR/summary.json and the deformed tissue every --mesh-every frames\n"
      "(DIR/mesh/*.vtu listed in DIR/SCENE.pvd: open it in ParaView, Warp By Vector). Each probe's\n"
      "contact patch starts on the tissue point nearest its trajectory's start and follows the probe\n"
      "along the surface.");
  cmd->add_option("scene", o->scene, "Scene file (.yaml)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--trajectory", o->trajectory, "The first probe's trajectory instead of the scene's (CSV t,x,y,z or a recording .h5)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--clock", o->clock,
                  "lockstep (simulated time, reproducible) or realtime (a 1 kHz haptic thread on the wall clock, a\n"
                  "solver thread and an I/O thread; the summary reports the tick period and the overruns)")->check(CLI::IsMember({"lockstep", "realtime"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "Output folder")->capture_default_str();
  cmd->add_option("--mesh-every", o->mesh_every, "Frames between deformed meshes written (0: none)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd->add_flag("--compare-ideal", o->compare_ideal,
                "Also run the ideal reference (the solver at the haptic rate, N = 1) and every local model and\n"
                "hold, and report each one's force error against it (RMS, peak, 2 % settling after the hold starts)");
  cmd->add_flag("--json", o->json, "Print the summary as JSON on stdout");
  cmd->callback([o, &exit_code]() { exit_code = run_replay(*o); });
}

}  // namespace fetouch::app
