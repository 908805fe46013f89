#include "app/trainer/trainer_window.h"

#include <QAction>
#include <QApplication>
#include <QComboBox>
#include <QFileDialog>
#include <QHBoxLayout>
#include <QImage>
#include <QLabel>
#include <QPixmap>
#include <QSplitter>
#include <QStatusBar>
#include <QTimer>
#include <QToolBar>
#include <QVBoxLayout>
#include <QVTKOpenGLStereoWidget.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkRenderer.h>

#include <cmath>
#include <sstream>

#include "app/log.h"
#include "app/scene_devices.h"
#include "app/trainer/review_window.h"
#include "app/trainer/trace_plot.h"
#include "app/trainer/ultrasound_volume.h"
#include "app/trainer/view_export.h"
#include "haptics/local_model.h"

namespace fetouch::app::trainer {

namespace {

constexpr int kImageSize = 256;
// The window's tick: it shows the newest ultrasound image, the plots and the status line, and asks
// for the next image, up to 50 times a second.
constexpr int kTickMs = 20;
// The 3D view renders at most every kViewPeriodS, and takes at most kViewShare of the window's
// thread: a software renderer's 37 ms render (Xvfb) was every tick's, so the view's rate was the
// ultrasound's too (14 images/s). Rendered every other tick or so instead, the ultrasound follows
// the solver and the probe (docs/trainer.md, "What the window draws, and how often").
constexpr double kViewPeriodS = 0.03, kViewShare = 2.0 / 3.0;
constexpr double kImageWidthM = 0.12, kImageDepthM = 0.10;

// The ultrasound image's plane: through `at`, looking along -normal, lateral along x or y.
SlicePlane image_plane(const Eigen::Vector3d& at, const Eigen::Vector3d& normal, bool lateral_x) {
  return probe_plane(at, normal, lateral_x ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY(), kImageWidthM, kImageDepthM,
                     kImageSize, kImageSize);
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

TrainerWindow::TrainerWindow(const config::Scene& scene, const TrainerOptions& session, const WindowOptions& window,
                             std::filesystem::path scene_path)
    : scene_(scene), session_options_(session), window_options_(window), scene_path_(std::move(scene_path)) {
  setWindowTitle(QString::fromStdString("Fetouch trainer: " + scene.name));
  volume_ = std::make_shared<const ReferenceVolume>(scene_ultrasound(scene_, gain_, volume_description_));

  vtk_widget_ = new QVTKOpenGLStereoWidget(this);
  auto render_window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  vtk_widget_->setRenderWindow(render_window);
  render_window_ = render_window;
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  // No multisampling: with software OpenGL (Xvfb, remote desktops) it costs most of a frame.
  render_window->SetMultiSamples(0);
  render_window_->AddRenderer(renderer);
  renderer_ = renderer;
  vtk_widget_->installEventFilter(this);
  vtk_widget_->setMinimumSize(560, 480);

  ultrasound_ = new QLabel(this);
  ultrasound_->setMinimumSize(kImageSize + 128, kImageSize + 128);
  ultrasound_->setAlignment(Qt::AlignCenter);
  ultrasound_->setStyleSheet("background: black");
  ultrasound_->setToolTip(QString::fromStdString("Ultrasound: " + volume_description_));
  force_plot_ = new TracePlot("force per probe (last 5 s)", "N", 5.0, this);
  frame_plot_ = new TracePlot("solver frame time (last 5 s)", "ms", 5.0, this);
  frame_plot_->set_series(1);
  margin_plot_ = new TracePlot("stability margin per frame (last 5 s; > 0: robustly stable)", "", 5.0, this);
  margin_plot_->set_series(1);
  energy_plot_ = new TracePlot("port energy per probe (last 5 s; < 0: the loop handed the hand energy)", "mJ", 5.0, this);
  auto* side = new QWidget(this);
  auto* column = new QVBoxLayout(side);
  if (window_options_.exercise.on) column->addWidget(build_exercise_panel(), 3);
  column->addWidget(ultrasound_, 3);
  column->addWidget(force_plot_, 1);
  column->addWidget(frame_plot_, 1);
  column->addWidget(margin_plot_, 1);
  column->addWidget(energy_plot_, 1);
  if (window_options_.exercise.on) {
    // A trainee's window: the guide where the stability margin and port energy plots were, and room
    // for the ultrasound image under it once the answer is shown.
    margin_plot_->hide(), energy_plot_->hide();
    ultrasound_->setMinimumSize(kImageSize + 8, kImageSize + 8);
  }
  auto* split = new QSplitter(this);
  split->addWidget(vtk_widget_);
  split->addWidget(side);
  split->setStretchFactor(0, 3), split->setStretchFactor(1, 2);
  split->setSizes({860, 420});  // of the window's 1,280 pixels
  setCentralWidget(split);
  status_ = new QLabel(this);
  message_ = new QLabel(this);
  statusBar()->addWidget(status_, 1);
  statusBar()->addPermanentWidget(message_);

  QToolBar* bar = addToolBar("controls");
  const auto action = [this, bar](const QString& text, const QKeySequence& key, auto&& f) {
    QAction* a = bar->addAction(text + " (" + key.toString() + ")");
    a->setShortcut(key);
    connect(a, &QAction::triggered, this, f);
  };
  action("Open", QKeySequence(Qt::CTRL | Qt::Key_O), [this] {
    const QString file = QFileDialog::getOpenFileName(this, "Open a scene", QString::fromStdString(scene_path_.parent_path().string()),
                                                      "Scenes (*.yaml *.yml)");
    if (!file.isEmpty()) open_scene(file.toStdString());
  });
  action("Pause", QKeySequence(Qt::Key_Space), [this] { toggle_pause(); });
  action("Reset", QKeySequence(Qt::Key_R), [this] { reset(); });
  action("Record", QKeySequence(Qt::CTRL | Qt::Key_R), [this] { toggle_recording(); });
  action("Screenshot", QKeySequence(Qt::CTRL | Qt::Key_S), [this] {
    const auto file = window_options_.out / ("screenshot-" + std::to_string(++screenshots_) + ".png");
    message_->setText(save_screenshot(file) ? QString::fromStdString("wrote " + file.string()) : "could not write the screenshot");
  });
  action("Colour", QKeySequence(Qt::Key_C), [this] { toggle_colour_field(); });
  action("Plane", QKeySequence(Qt::Key_O), [this] { toggle_plane(); });
  action("Camera", QKeySequence(Qt::Key_V), [this] { reset_camera(); });
  // Local model and hold: a choice is asked of the session, whose stability analysis accepts it
  // (with gains re-selected) or refuses it (the boxes go back, the reason on the message line).
  {
    const haptics::HapticLoopSettings scene_loop = loop_settings(scene_);
    model_ = asked_model_ = scene_loop.local_model, hold_ = asked_hold_ = scene_loop.hold;
  }
  model_box_ = new QComboBox(this);
  for (const auto kind : {haptics::LocalModelKind::p, haptics::LocalModelKind::pi, haptics::LocalModelKind::smith,
                          haptics::LocalModelKind::pi_smith})
    model_box_->addItem(haptics::to_string(kind), static_cast<int>(kind));
  model_box_->setToolTip("local model (M: the next one)");
  hold_box_ = new QComboBox(this);
  for (const auto kind : {haptics::HoldKind::zoh, haptics::HoldKind::foh}) hold_box_->addItem(haptics::to_string(kind), static_cast<int>(kind));
  hold_box_->setToolTip("hold (H: the other one)");
  show_mode();
  bar->addWidget(model_box_);
  bar->addWidget(hold_box_);
  const auto asked_from_boxes = [this](int) {
    ask_mode(static_cast<haptics::LocalModelKind>(model_box_->currentData().toInt()),
             static_cast<haptics::HoldKind>(hold_box_->currentData().toInt()));
  };
  connect(model_box_, QOverload<int>::of(&QComboBox::activated), this, asked_from_boxes);
  connect(hold_box_, QOverload<int>::of(&QComboBox::activated), this, asked_from_boxes);
  action("Model", QKeySequence(Qt::Key_M), [this] {
    ask_mode(static_cast<haptics::LocalModelKind>((static_cast<int>(asked_model_) + 1) % 4), asked_hold_);
  });
  action("Hold", QKeySequence(Qt::Key_H), [this] {
    ask_mode(asked_model_, asked_hold_ == haptics::HoldKind::zoh ? haptics::HoldKind::foh : haptics::HoldKind::zoh);
  });
  action("Hand", QKeySequence(Qt::Key_Tab), [this] { switch_hand(); });
  action("Quit", QKeySequence(Qt::CTRL | Qt::Key_Q), [this] { close(); });
  addToolBarBreak();
  regions_bar_ = addToolBar("regions");
  regions_bar_->setToolTip("show or hide each region's surfaces");

  resize(1280, 800);
  if (window_options_.exercise.on) {
    // The exercise's take is recorded: its assessment is made from the recording.
    std::error_code ignored;
    std::filesystem::create_directories(window_options_.out / "exercise", ignored);
    start_take(window_options_.out / "exercise" / "take.h5");
    hide_the_answer(true);
    show_exercise_step();
  } else {
    start_take(std::nullopt);
  }
  timer_ = new QTimer(this);
  connect(timer_, &QTimer::timeout, this, [this] { tick(); });
  timer_->start(kTickMs);
  started_ = rate_from_ = std::chrono::steady_clock::now();
  cpu_ = sample_cpu();
}

bool TrainerWindow::set_region_visible(const std::string& name, bool on) {
  if (on)
    hidden_regions_.erase(name);
  else
    hidden_regions_.insert(name);
  bool found = false;
  for (std::size_t i = 0; view_ && i < view_->regions(); ++i)
    if (view_->region_name(i) == name) view_->set_region_visible(i, on), found = true;
  for (QAction* a : regions_bar_->actions())
    if (a->text().toStdString() == name && a->isChecked() != on) {
      const QSignalBlocker quiet(a);
      a->setChecked(on);
    }
  if (found) render_window_->Render();
  return found;
}

TrainerWindow::~TrainerWindow() {
  if (timer_) timer_->stop();
  view_.reset();
  session_.reset();  // stops and joins the session's thread
}

void TrainerWindow::start_take(const std::optional<std::filesystem::path>& recording) {
  if (session_) session_->request_stop();
  session_.reset();
  view_.reset();
  imager_.reset();
  if (renderer_) renderer_->RemoveAllViewProps();
  TrainerOptions options = session_options_;
  options.recording = recording;
  recording_ = recording;
  std::vector<std::string> messages;
  QApplication::setOverrideCursor(Qt::WaitCursor);
  try {
    session_ = std::make_unique<TrainerSession>(scene_, options, messages);
  } catch (const std::exception& e) {
    QApplication::restoreOverrideCursor();
    figures_.error = e.what();
    message_->setText(QString::fromStdString("error: " + figures_.error));
    return;
  }
  QApplication::restoreOverrideCursor();
  std::vector<double> radii;
  for (const auto& p : session_->scene().probes) radii.push_back(p.radius_m);
  // A mesh whose regions were voted onto its elements draws its label map's smooth surfaces, not
  // the staircase of element faces between them (label_surfaces.h).
  std::vector<LabelSurface> smooth;
  try {
    double made_s = -1;
    smooth = scene_label_surfaces(scene_, session_->mesh(), smooth_, made_s);
    std::size_t triangles = 0;
    for (const auto& s : smooth) triangles += s.triangles.size();
    if (made_s >= 0 && triangles > 0)
      log::info() << "the regions drawn as their label map's smooth surfaces: " << triangles << " triangles, made in "
                  << made_s << " s";
  } catch (const std::exception& e) {
    messages.push_back(std::string("the regions are drawn as the mesh has them (") + e.what() + ")");
  }
  view_ = std::make_unique<TissueView>(renderer_, session_->mesh(), radii, std::move(smooth));
  imager_ = std::make_unique<UltrasoundImager>(session_->mesh().points, session_->mesh().tetrahedra, session_->mesh().material,
                                               volume_, gain_);
  force_plot_->set_series(static_cast<int>(radii.size()));
  force_plot_->clear();
  frame_plot_->clear();
  frame_plot_->set_limit(1e3 * session_->solver_period_s(), "budget");
  margin_plot_->clear();
  margin_plot_->set_limit(0, "unstable below");
  energy_plot_->set_series(static_cast<int>(radii.size()));
  energy_plot_->clear();
  energy_plot_->set_limit(0, "generated below");
  last_frame_ = -2, rate_frames_ = 0, overruns_ = 0, imaged_frame_ = -3;
  session_->want_stress(field_ == ColourField::von_mises);
  if (session_->take_snapshot()) shown_ = session_->snapshot();
  // Each mouse probe's cursor 1 cm out from its patch; the mouse drives the first.
  cursor_targets_.assign(radii.size(), Eigen::Vector3d::Zero());
  for (int p = 0; p < static_cast<int>(radii.size()); ++p)
    if (haptics::CursorOperator* c = session_->cursor_of(p)) {
      if (p < static_cast<int>(shown_.patch_centre.size())) cursor_targets_[p] = shown_.patch_centre[p] + 0.01 * shown_.patch_normal[p];
      c->set_target(cursor_targets_[p]);
    }
  if (session_->cursor()) cursor_ = cursor_targets_[session_->cursor_probe()];
  view_->update_tissue(shown_, field_);
  view_->show_cursor(session_->cursor() != nullptr, cursor_);
  regions_bar_->clear();
  regions_bar_->setVisible(view_->regions() > 0);  // a scene of one region has nothing to toggle
  for (std::size_t i = 0; i < view_->regions(); ++i) {
    const std::string name = view_->region_name(i);
    QAction* a = regions_bar_->addAction(QString::fromStdString(name));
    a->setCheckable(true);
    a->setChecked(!hidden_regions_.count(name));
    a->setToolTip(QString::fromStdString("show or hide the surfaces of " + name));
    view_->set_region_visible(i, a->isChecked());
    connect(a, &QAction::toggled, this, [this, name](bool on) { set_region_visible(name, on); });
  }
  reset_camera();
  std::string text;
  for (const auto& m : messages) text += m + "  ";
  if (recording) {
    text += "recording to " + recording->string();
    // The mesh the take is made on, beside it: `fetouch review` draws the take over it.
    const std::filesystem::path anatomy = anatomy_beside(*recording);
    try {
      write_tissue_vtu(session_->mesh(), {}, anatomy);
    } catch (const std::exception& e) {
      text += " (" + std::string(e.what()) + ": the take cannot be reviewed)";
    }
  }
  message_->setText(QString::fromStdString(text));
  ++takes_;
  mode_request_ = 0;
  // The session's clock starts at the window's next tick, once the view has been drawn: the first
  // render (software OpenGL compiles its shaders then) takes up to a second, which would otherwise
  // pass unseen in the take.
  start_pending_ = true;
  // A new take starts in the scene's mode; one chosen since is asked again (and analysed again).
  const haptics::HapticLoopSettings& scene_loop = session_->loop();
  if (model_ != scene_loop.local_model || hold_ != scene_loop.hold) {
    const haptics::LocalModelKind model = model_;
    const haptics::HoldKind hold = hold_;
    model_ = asked_model_ = scene_loop.local_model, hold_ = asked_hold_ = scene_loop.hold;
    show_mode();
    ask_mode(model, hold);
  }
}

void TrainerWindow::tick() {
  if (!session_) {
    if (window_options_.headless) close();
    return;
  }
  if (start_pending_) {
    render_window_->Render();
    session_->start();
    start_pending_ = false;
    take_started_ = std::chrono::steady_clock::now(), take_images_ = figures_.ultrasound_images;
    take_renders_ = figures_.renders;
    // The status line's rates count from here, not from before the take was built.
    rate_from_ = take_started_;
    rate_ticks_ = session_->monitor().ticks.load(), rate_frames_ = last_frame_, rate_images_ = figures_.ultrasound_images;
    rate_renders_ = figures_.renders;
  }
  take_mode_verdict();
  exercise_tick();
  if (session_->take_snapshot()) {
    shown_ = session_->snapshot();
    view_->update_tissue(shown_, field_);
    if (shown_.frame != last_frame_) {
      if (shown_.solve_s > session_->solver_period_s()) ++overruns_;
      frame_plot_->add(0, shown_.time_s, 1e3 * shown_.solve_s);
      margin_plot_->add(0, shown_.time_s, shown_.stability_margin);
      last_frame_ = shown_.frame;
    }
  }
  SessionMonitor& monitor = session_->monitor();
  const int probes = static_cast<int>(session_->probe_names().size());
  if (monitor.probes.take()) {
    const auto& p = monitor.probes.front();
    view_->update_probes(p, probes);
    const double t = monitor.ticks.load() * session_->loop().period_s;
    for (int i = 0; i < probes && i < SessionMonitor::kMaxDevices; ++i) {
      force_plot_->add(i, t, p[i].force.norm());
      energy_plot_->add(i, t, 1e3 * p[i].port_energy_j);
    }
    last_probes_ = p;
  }
  // The image plane follows the probe at the window's rate (through its proxy on the surface while
  // it touches, else through its patch), the tissue in it at the solver's: a new image is asked for
  // when either moved, and made while the view renders; the newest made is shown.
  const bool hidden = window_options_.exercise.on && step_ <= exercise::kManeuvers;  // no image until answered
  if (!shown_.patch_centre.empty() && !hidden) {
    const int probe = std::max(0, session_->cursor_probe());
    const SessionMonitor::ProbeTick& t = monitor.probes.front()[probe];
    const Eigen::Vector3d at = t.in_contact ? t.proxy : shown_.patch_centre[probe];
    if (shown_.frame != imaged_frame_ || (at - imaged_at_).norm() > 5e-5) {
      plane_ = image_plane(at, shown_.patch_normal[probe], lateral_x_);
      imager_->request(shown_.frame, shown_.displacement, plane_);
      ++figures_.ultrasound_asked;
      imaged_frame_ = shown_.frame, imaged_at_ = at;
    }
  }
  if (imager_->take(image_)) show_ultrasound();
  if (view_due()) {
    rendered_at_ = std::chrono::steady_clock::now();
    render_window_->Render();
    render_s_ = seconds_since(rendered_at_);
    ++figures_.renders;
    figures_.render_seconds += render_s_;
  }
  force_plot_->update();
  frame_plot_->update();
  margin_plot_->update();
  energy_plot_->update();
  update_status();
  if (!session_->running() && window_options_.headless) {
    figures_.error = session_->error();
    // A scripted exercise answers when its take ends (what it was given, else nothing).
    if (figures_.error.empty() && window_options_.exercise.on && step_ <= exercise::kManeuvers) {
      const exercise::Answers given = window_options_.exercise.answers.value_or(exercise::Answers{});
      if (window_options_.exercise.step_screenshots) {  // the answers step as the trainee sees it
        step_ = exercise::kManeuvers;
        show_exercise_step();
        choose_answers(given);
        picture_step("answers.png");
      }
      answer(given);
    }
    if (window_options_.screenshot && figures_.error.empty()) {
      if (!save_screenshot(*window_options_.screenshot))
        figures_.error = "cannot write the screenshot " + window_options_.screenshot->string();
      else
        export_views(*window_options_.screenshot);
    }
    figures_.wall_s = seconds_since(started_);
    figures_.ultrasound_per_s = (figures_.ultrasound_images - take_images_) / seconds_since(take_started_);
    figures_.renders_per_s = (figures_.renders - take_renders_) / seconds_since(take_started_);
    timer_->stop();
    close();
  }
}

bool TrainerWindow::view_due() const {
  return seconds_since(rendered_at_) >= std::max(kViewPeriodS, render_s_ / kViewShare);
}

void TrainerWindow::image_now() {
  if (!session_ || !imager_ || shown_.patch_centre.empty()) return;
  const int probe = std::max(0, session_->cursor_probe());
  plane_ = image_plane(shown_.patch_centre[probe], shown_.patch_normal[probe], lateral_x_);
  imager_->make_now(shown_.frame, shown_.displacement, plane_, image_);
  imaged_frame_ = shown_.frame, imaged_at_ = shown_.patch_centre[probe];
  // The image's label may just have been shown: laid out first, so that the picture fits it.
  if (QLayout* column = ultrasound_->parentWidget()->layout()) column->activate();
  show_ultrasound();
}

void TrainerWindow::show_ultrasound() {
  const SlicePlane& p = image_.plane;
  QImage picture(image_.pixels.data(), p.columns, p.rows, p.columns, QImage::Format_Grayscale8);
  const int side = std::min(ultrasound_->width(), ultrasound_->height()) - 4;
  ultrasound_->setPixmap(QPixmap::fromImage(picture).scaled(side, side, Qt::KeepAspectRatio, Qt::SmoothTransformation));
  figures_.ultrasound_seconds += image_.seconds;
  ++figures_.ultrasound_images;
}

void TrainerWindow::update_status() {
  const double span = seconds_since(rate_from_);
  SessionMonitor& monitor = session_->monitor();
  if (span >= 1.0) {
    haptic_hz_ = (monitor.ticks.load() - rate_ticks_) / span;
    // The solver's rate from the frames it answered (the window may show fewer when it is slower).
    solver_hz_ = std::max(0.0, (last_frame_ - rate_frames_) / span);
    ultrasound_hz_ = (figures_.ultrasound_images - rate_images_) / span;
    view_hz_ = (figures_.renders - rate_renders_) / span;
    const CpuSample cpu = sample_cpu();
    others_cores_ = others_cores(cpu_, cpu);
    cpu_ = cpu;
    figures_.others_cores_max = std::max(figures_.others_cores_max, others_cores_);
    if (others_cores_ >= kBusyCores) figures_.busy_s += span;
    rate_ticks_ = monitor.ticks.load(), rate_frames_ = last_frame_, rate_images_ = figures_.ultrasound_images;
    rate_renders_ = figures_.renders;
    rate_from_ = std::chrono::steady_clock::now();
  }
  const haptics::HapticLoopSettings& loop = session_->loop();
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << (session_->paused() ? "PAUSED  " : session_->running() ? "" : "ENDED  ");
  // Another program's load slows the view and the ultrasound (they share the cores with it), not
  // the solver, whose thread is ahead of them all where it may be (TimingSummary::solver_nice).
  if (others_cores_ >= kBusyCores) {
    s.precision(1);
    s << "BUSY (other programs use " << others_cores_ << " of " << cpu_.cpus << " cores): view " << std::lround(view_hz_)
      << " Hz, " << (monitor.solver_nice.load() < 0 ? "the solver first   " : "the solver slowed too   ");
    s.precision(2);
  }
  s << "t " << monitor.ticks.load() * loop.period_s
    << " s   haptic " << std::lround(haptic_hz_) << " Hz   solver " << std::lround(solver_hz_) << " Hz   "
    << haptics::to_string(model_) << " / " << haptics::to_string(hold_) << "   Kp " << std::lround(shown_.proportional_gain)
    << " Ki " << std::lround(shown_.integral_gain) << "   margin " << shown_.stability_margin << "   late ticks "
    << monitor.late_ticks.load() << "   overruns " << overruns_ << "   ultrasound " << std::lround(ultrasound_hz_)
    << " img/s   view " << std::lround(view_hz_) << " Hz";
  // What the hand feels: the passivity layer when it scales a probe's force, and the identified
  // stiffness against the frame's (docs/stability.md, sections 9 and 10).
  const std::vector<std::string>& names = session_->probe_names();
  for (std::size_t i = 0; i < names.size() && i < last_probes_.size(); ++i) {
    const SessionMonitor::ProbeTick& p = last_probes_[i];
    if (p.passivity_scale < 0.999) s << "   PASSIVITY: " << names[i] << " scaled to " << std::lround(100 * p.passivity_scale) << " %";
    if (p.in_contact && p.identified_stiffness_n_per_m > 0)
      s << "   " << names[i] << " felt " << std::lround(p.identified_stiffness_n_per_m) << " / tissue "
        << std::lround(p.condensed_stiffness_n_per_m) << " N/m";
  }
  if (session_->cursor()) {
    s << "   mouse: shift+move, shift+wheel or [ ] to push";
    if (session_->mouse_probes() > 1) s << " " << session_->probe_names()[session_->cursor_probe()] << " (Tab: the next hand)";
  }
  status_->setText(QString::fromStdString(s.str()));
}

}  // namespace fetouch::app::trainer
