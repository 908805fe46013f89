// `fetouch trainer`: the surgical trainer's window on a scene (app/trainer/trainer_window.h).
#include <CLI/CLI.hpp>
#include <QApplication>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/chart_png.h"
#include "app/cli.h"
#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/mpi_session.h"
#include "app/realtime_cores.h"
#include "app/scene_mesh.h"
#include "app/session.h"
#include "app/trainer/trainer_window.h"

namespace fetouch::app {

namespace {

struct TrainerCommandOptions {
  std::string scene, trajectory, screenshot, out = "fetouch-trainer";
  double duration_s = 0;
  bool mouse = false, json = false;
  std::string exercise, answers, clock = "realtime", step_screenshots;
  std::uint32_t seed = 1;
  std::vector<double> maneuver_times;
  double comfort_limit_n = 0;
};

// --exercise's settings on the scene (its phantom's seed and a pose drawn from it) and the window;
// false (the reason on standard error) when they cannot be.
bool set_up_exercise(const TrainerCommandOptions& o, config::Scene& scene, trainer::ExerciseOptions& e) {
  if (o.exercise.empty()) {
    if (!o.answers.empty() || !o.maneuver_times.empty() || !o.step_screenshots.empty()) {
      std::cerr << "error: --answers, --maneuvers and --step-screenshots belong to an exercise: add --exercise leopold\n";
      return false;
    }
    return true;
  }
  if (o.exercise != "leopold") {
    std::cerr << "error: --exercise " << o.exercise << ": the exercises are: leopold\n";
    return false;
  }
  if (scene.mesh.source != config::MeshSource::phantom) {
    std::cerr << "error: " << o.scene << ": the Leopold exercise needs a phantom scene (mesh.phantom), such as "
                 "config/scenes/leopold.yaml\n";
    return false;
  }
  e.on = true;
  scene.mesh.phantom.seed = static_cast<int>(o.seed);
  scene.mesh.phantom.pose = config::draw_pose(o.seed);
  if (!o.maneuver_times.empty()) {
    if (o.maneuver_times.size() != 3 || !(o.maneuver_times[0] <= o.maneuver_times[1] && o.maneuver_times[1] <= o.maneuver_times[2])) {
      std::cerr << "error: --maneuvers takes three times in order (s): when the second, third and fourth maneuvers begin\n";
      return false;
    }
    e.maneuver_times = std::array<double, 3>{o.maneuver_times[0], o.maneuver_times[1], o.maneuver_times[2]};
  }
  if (!o.answers.empty()) {
    std::vector<std::string> names;
    std::string name;
    for (std::istringstream in(o.answers); std::getline(in, name, ',');) names.push_back(name);
    exercise::Answers a;
    config::FetalLie lie;
    config::FetalPresentation presentation;
    config::FetalBack back;
    if (names.size() != 3 || !config::parse(names[0], lie) || !config::parse(names[1], presentation) || !config::parse(names[2], back)) {
      std::cerr << "error: --answers " << o.answers << ": give LIE,PRESENTATION,BACK by their names (docs/scenes.md), e.g. "
                   "longitudinal,cephalic,left_anterior\n";
      return false;
    }
    e.answers = exercise::Answers{lie, presentation, back};
  }
  if (!o.step_screenshots.empty()) e.step_screenshots = o.step_screenshots;
  if (o.comfort_limit_n > 0) {
    e.comfort_limit_n = o.comfort_limit_n;
    e.comfort_limit_source = "given on the command line (--comfort-limit)";
  }
  return true;
}

int run_trainer(const TrainerCommandOptions& o) {
  if (!window_display_available()) {
    std::cerr << "error: fetouch trainer opens a window and there is no display (DISPLAY is not set); "
                 "on a machine without one run it under a virtual display: xvfb-run -a fetouch trainer ...\n";
    return kExitBadInput;
  }
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  if (loaded->probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes to touch the tissue with\n";
    return kExitBadInput;
  }
  if (!o.screenshot.empty() && o.duration_s <= 0) {
    std::cerr << "error: --screenshot needs --duration: the screenshot is taken when the session ends\n";
    return kExitBadInput;
  }
  trainer::ExerciseOptions exercise;
  if (!set_up_exercise(o, *loaded, exercise)) return kExitBadInput;
  ensure_mpi();
  // The window, and the threads of a software OpenGL renderer, share the haptic thread's core
  // (which it preempts at every tick) and leave the solver its own; there the window runs ahead of
  // other programs (kWindowNice), as the solver does on its core (kSolverNice).
  share_haptic_core();
  const int window_nice = raise_thread_priority(kWindowNice);
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  static int argc = 1;
  static char name[] = "fetouch";
  static char* argv[] = {name, nullptr};
  QApplication application(argc, argv);
  trainer::TrainerOptions session;
  if (!o.trajectory.empty()) session.trajectory = o.trajectory;
  session.mouse = o.mouse;
  session.duration_s = o.duration_s;
  session.lockstep = o.clock == "lockstep";
  trainer::WindowOptions window;
  window.out = o.out;
  if (!o.screenshot.empty()) window.screenshot = o.screenshot;
  window.headless = o.duration_s > 0;
  window.exercise = exercise;
  std::unique_ptr<trainer::TrainerWindow> w;
  try {
    w = std::make_unique<trainer::TrainerWindow>(*loaded, session, window, o.scene);
  } catch (const std::exception& e) {
    std::cerr << "error: " << o.scene << ": " << e.what() << "\n";
    return kExitBadInput;
  }
  if (!w->session()) {
    std::cerr << "error: " << o.scene << ": " << w->figures().error << "\n";
    return kExitBadInput;
  }
  w->show();
  application.exec();
  const trainer::WindowFigures& f = w->figures();
  const SessionSummary s = w->session() ? w->session()->summary() : SessionSummary{};
  if (!f.error.empty()) {
    std::cerr << "error: " << o.scene << ": " << f.error << "\n";
    return kExitFailure;
  }
  const double image_ms = f.ultrasound_images > 0 ? 1e3 * f.ultrasound_seconds / f.ultrasound_images : 0;
  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("scene").value(loaded->name);
    json.key("ticks").value(s.ticks);
    json.key("frames").value(s.frames);
    json.key("solve_p99_s").value(s.solve_p99_s);
    json.key("max_force_n").value(s.max_force_n);
    json.key("tick_lateness_p99_s").value(s.timing.lateness_p99_s);
    json.key("tick_lateness_max_s").value(s.timing.lateness_max_s);
    json.key("late_ticks").value(s.timing.tick_overruns);
    json.key("frame_overruns").value(s.timing.frame_overruns);
    json.key("skipped_frames").value(s.timing.skipped_frames);
    json.key("solver_differences").value(s.timing.solver_differences);
    json.key("ultrasound_asked").value(f.ultrasound_asked);
    json.key("ultrasound_images").value(f.ultrasound_images);
    json.key("ultrasound_image_ms").value(image_ms);
    json.key("ultrasound_images_per_s").value(f.ultrasound_per_s);
    json.key("renders").value(f.renders);
    json.key("renders_per_s").value(f.renders_per_s);
    json.key("render_ms").value(f.renders > 0 ? 1e3 * f.render_seconds / f.renders : 0.0);
    json.key("solver_nice").value(static_cast<long>(s.timing.solver_nice));
    json.key("window_nice").value(static_cast<long>(window_nice));
    json.key("others_cores_max").value(f.others_cores_max);
    json.key("busy_s").value(f.busy_s);
    json.key("wall_s").value(f.wall_s);
    json.key("screenshot").value(o.screenshot);
    if (f.assessment) {
      const exercise::Assessment& a = *f.assessment;
      json.key("exercise").begin_object();
      json.key("pose").value(config::describe(a.pose));
      json.key("assessment").value((f.assessment_dir / "assessment.json").string());
      json.key("answer_score").value(a.answer_score());
      json.key("maneuvers_reached").value(a.maneuvers_reached());
      json.key("covered_share").value(a.covered_share);
      json.key("largest_force_n").value(a.largest_force_n);
      json.end_object();
    }
    if (!f.ultrasound_png.empty()) {
      const auto vector = [&json](const Eigen::Vector3d& v) {
        json.begin_array();
        for (int c = 0; c < 3; ++c) json.value(v[c]);
        json.end_array();
      };
      json.key("ultrasound_view").begin_object();
      json.key("image").value(f.ultrasound_png.string());
      json.key("tissue").value(f.tissue_vtu.string());
      json.key("frame").value(f.frame);
      json.key("volume").value(f.volume);
      json.key("gain").value(f.gain);
      json.key("centre_m");
      vector(f.plane.centre);
      json.key("lateral");
      vector(f.plane.lateral);
      json.key("up");
      vector(f.plane.up);
      json.key("width_m").value(f.plane.width_m);
      json.key("height_m").value(f.plane.height_m);
      json.key("columns").value(static_cast<long>(f.plane.columns));
      json.key("rows").value(static_cast<long>(f.plane.rows));
      json.end_object();
    }
    json.end_object();
    std::cout << "\n";
  } else {
    std::printf("%ld ticks, %ld frames; solve p99 %.1f ms; tick lateness p99 %.1f us, max %.1f us, %ld late ticks; "
                "%ld frame overruns, %ld skipped\n",
                s.ticks, s.frames, 1e3 * s.solve_p99_s, 1e6 * s.timing.lateness_p99_s, 1e6 * s.timing.lateness_max_s,
                s.timing.tick_overruns, s.timing.frame_overruns, s.timing.skipped_frames);
    std::printf("  ultrasound: %ld images of 256 x 256 shown of %ld asked for, %.1f per second, %.1f ms each to make; "
                "%ld renders\n", f.ultrasound_images, f.ultrasound_asked, f.ultrasound_per_s, image_ms, f.renders);
    if (f.busy_s > 0)
      std::printf("  the machine was busy for %.0f s (other programs used up to %.1f cores); the solver ran at nice %d, "
                  "the window at %d\n", f.busy_s, f.others_cores_max, s.timing.solver_nice, window_nice);
    if (!o.screenshot.empty())
      std::printf("  wrote %s, %s (the ultrasound image) and %s (the tissue shown)\n", o.screenshot.c_str(),
                  f.ultrasound_png.c_str(), f.tissue_vtu.c_str());
  }
  return kExitOk;
}

}  // namespace

void add_trainer_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<TrainerCommandOptions>();
  CLI::App* cmd = parent.add_subcommand("trainer", drawing_command_description("trainer"));
  cmd->footer(
      "Runs the scene's real-time session in a window: the deformed tissue (3D), the ultrasound image\n"
      "in the first probe's plane through the deformed tissue, force and frame-time plots, and a status\n"
      "line. Probes with a trajectory play it; `type: mouse` probes (or the first, with --mouse) follow\n"
      "the mouse: shift+move moves the cursor in the view plane, shift+wheel or [ and ] push it along\n"
      "the view; the probe follows through a spring, so its lag is the force. Keys: space pause, R\n"
      "reset, ctrl+R record a take (DIR/take-N.h5, replayable with `fetouch replay --trajectory`),\n"
      "ctrl+S screenshot, C colour field, O image plane, V camera, M local model and H hold (applied\n"
      "if the stability analysis accepts them), ctrl+O open a scene. With --duration it runs that long,\n"
      "writes --screenshot and exits (docs, tests, bug reports). Needs a display: xvfb-run -a.\n"
      "--exercise leopold [--seed S] on a phantom scene (config/scenes/leopold.yaml): the four Leopold\n"
      "maneuvers guided one by one with the fetus and the ultrasound hidden (N: the next), then the lie,\n"
      "presentation and position to answer; the assessment goes to OUT/exercise (docs/trainer.md).");
  cmd->add_option("scene", o->scene, "Scene file (.yaml)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--trajectory", o->trajectory, "The first probe's trajectory instead of the scene's (CSV t,x,y,z or a recording .h5)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--mouse", o->mouse, "The mouse drives the first probe");
  cmd->add_option("--duration", o->duration_s, "Run this long (s), then write --screenshot and exit")->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--screenshot", o->screenshot, "PNG written when the session ends (with --duration)");
  cmd->add_option("--out", o->out, "Folder for takes and screenshots")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print the summary as JSON on stdout");
  cmd->add_option("--clock", o->clock, "realtime (a 1 kHz haptic thread on the wall clock), or lockstep (simulated time: "
                                       "scripted probes only, the take reproducible and as fast as the solver goes)")
      ->check(CLI::IsMember({"realtime", "lockstep"}))
      ->capture_default_str();
  cmd->add_option("--exercise", o->exercise, "An exercise on the scene's phantom: leopold (the four Leopold maneuvers, then "
                                             "the fetus's lie, presentation and position to answer; docs/trainer.md)");
  cmd->add_option("--seed", o->seed, "The exercise's fetus: the phantom's seed and the pose drawn from it")->capture_default_str();
  cmd->add_option("--maneuvers", o->maneuver_times, "Scripted: the simulated times (s) at which maneuvers 2, 3 and 4 begin")
      ->delimiter(',')->expected(3);
  cmd->add_option("--answers", o->answers, "Scripted: LIE,PRESENTATION,BACK, given when the take ends (with --duration)");
  cmd->add_option("--step-screenshots", o->step_screenshots, "Pictures of the exercise's steps to this folder: step-K.png 1.7 s "
                                                             "into maneuver K, answers.png before answering (docs)");
  cmd->add_option("--comfort-limit", o->comfort_limit_n, "The exercise's comfort limit for the force (N; none by default)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->callback([o, &exit_code]() { exit_code = run_trainer(*o); });
}

}  // namespace fetouch::app
