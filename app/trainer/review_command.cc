// `fetouch review`: a recorded take played back over its anatomy (app/trainer/review_window.h).
#include <CLI/CLI.hpp>
#include <QApplication>
#include <QSurfaceFormat>
#include <QTimer>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkCamera.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>

#include "app/chart_png.h"
#include "app/cli.h"
#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/trainer/review_window.h"

namespace fetouch::app {

namespace {

struct ReviewCommandOptions {
  std::string dir, take, screenshot;
  double at_s = -1;
  bool no_paths = false, json = false;
};

int run_review(const ReviewCommandOptions& o) {
  trainer::ReviewTake take;
  try {
    take = trainer::load_review_take(o.dir, o.take);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  }
  if (o.at_s > take.duration_s + 1e-9) {
    std::fprintf(stderr, "error: --at %g: the take lasts %.3f s\n", o.at_s, take.duration_s);
    return kExitBadInput;
  }
  if (!window_display_available()) {
    std::cerr << "error: fetouch review opens a window and there is no display (DISPLAY is not set); "
                 "on a machine without one run it under a virtual display: xvfb-run -a fetouch review ... --screenshot FILE.png\n";
    return kExitBadInput;
  }
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  static int argc = 1;
  static char name[] = "fetouch";
  static char* argv[] = {name, nullptr};
  QApplication application(argc, argv);
  trainer::ReviewOptions options;
  options.at_s = o.at_s;
  options.paths = !o.no_paths;
  trainer::ReviewWindow window(std::move(take), options);
  window.show();
  bool written = true;
  if (!o.screenshot.empty()) {
    // Headless: once the window is up and drawn, the picture, then out.
    QTimer::singleShot(300, &window, [&] {
      window.show_time(window.time_shown());
      written = window.save_screenshot(o.screenshot);
      window.close();
    });
  }
  application.exec();
  if (!written) {
    std::cerr << "error: " << o.screenshot << ": the screenshot cannot be written\n";
    return kExitFailure;
  }
  const trainer::ReviewTake& t = window.take();
  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("take").value(t.recording_file.string());
    json.key("anatomy").value(t.anatomy_file.string());
    json.key("duration_s").value(t.duration_s);
    json.key("at_s").value(window.time_shown());
    json.key("probes").begin_array();
    for (const RecordedDevice& d : t.recording.devices) {
      double contact_s = 0, largest = 0;
      for (std::size_t i = 1; i < d.samples.size(); ++i)
        if (d.samples[i].in_contact) contact_s += d.samples[i].time_s - d.samples[i - 1].time_s, largest = std::max(largest, d.samples[i].force.norm());
      json.begin_object().key("name").value(d.name).key("samples").value(static_cast<long>(d.samples.size()));
      json.key("in_contact_s").value(contact_s).key("largest_force_n").value(largest).end_object();
    }
    json.end_array();
    json.key("paths").value(!o.no_paths);
    json.key("path_force_range_n").value(window.path_force_range_n());
    json.key("exercise").value(t.scores.has_value());
    if (t.scores) json.key("answer_score").value(t.scores->answer_score());
    json.key("screenshot").value(o.screenshot);
    // Where the 3D view is in the screenshot, and its camera: enough to find a point's pixel.
    const trainer::ReviewWindow::Rect r = window.view_rect();
    json.key("view").begin_object().key("x").value(r.x).key("y").value(r.y).key("width").value(r.width).key("height").value(r.height).end_object();
    vtkCamera* c = window.camera();
    const auto vector = [&json](const double* v) {
      json.begin_array();
      for (int k = 0; k < 3; ++k) json.value(v[k]);
      json.end_array();
    };
    json.key("camera").begin_object();
    json.key("position");
    vector(c->GetPosition());
    json.key("focal_point");
    vector(c->GetFocalPoint());
    json.key("view_up");
    vector(c->GetViewUp());
    json.key("view_angle_deg").value(c->GetViewAngle());
    json.key("parallel").value(static_cast<bool>(c->GetParallelProjection()));
    json.end_object();
    json.end_object();
    std::cout << "\n";
  } else if (!o.screenshot.empty()) {
    std::printf("wrote %s: the take of %.1f s at %.3f s\n", o.screenshot.c_str(), t.duration_s, window.time_shown());
  }
  return kExitOk;
}

}  // namespace

void add_review_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<ReviewCommandOptions>();
  CLI::App* cmd = parent.add_subcommand("review", drawing_command_description("review"));
  cmd->footer(
      "Plays a recorded take back over the anatomy it was made on: the probes' paths drawn over it\n"
      "(pressing: coloured by the force, green to red; moving: thin grey), each probe's tool, contact\n"
      "point and force at the time on the slider (drag it, or space to play at the take's pace; P shows\n"
      "or hides the paths), the forces against time, and an exercise's scores and coverage map.\n"
      "DIR is a take's folder: OUT/exercise of `fetouch trainer --exercise` (take.h5, anatomy.vtu,\n"
      "assessment.json, coverage.png), or the trainer's OUT with --take take-N.h5 for a ctrl+R take.\n"
      "With --screenshot it draws the time --at, writes the PNG and exits (docs, tests). Needs a\n"
      "display: xvfb-run -a.");
  cmd->add_option("dir", o->dir, "The take's folder")->required();
  cmd->add_option("--take", o->take, "The recording in DIR (default take.h5)");
  cmd->add_option("--at", o->at_s, "The time shown first (s; default the take's end)")->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--screenshot", o->screenshot, "Write this PNG of the window at --at and exit");
  cmd->add_flag("--no-paths", o->no_paths, "Start with the paths hidden");
  cmd->add_flag("--json", o->json, "Print what was shown as JSON on stdout (with the view's camera)");
  cmd->callback([o, &exit_code]() { exit_code = run_review(*o); });
}

}  // namespace fetouch::app
