#include "app/trainer/review_window.h"

#include <QHBoxLayout>
#include <QLabel>
#include <QPainter>
#include <QPainterPath>
#include <QPixmap>
#include <QPushButton>
#include <QSlider>
#include <QSplitter>
#include <QStatusBar>
#include <QTimer>
#include <QToolBar>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkLookupTable.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextProperty.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <optional>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "app/trainer/view_export.h"
#include "config/scene_loader.h"

namespace fetouch::app::trainer {

namespace fs = std::filesystem;

namespace {

ReviewScores read_scores(const fs::path& file) {
  YAML::Node a;
  try {
    a = YAML::LoadFile(file.string());
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + ": cannot be read as JSON: " + e.what());
  }
  ReviewScores s;
  try {
    s.pose = a["pose"]["description"].as<std::string>();
    for (const auto& r : a["answers"])
      s.answers.push_back({r["asked"].as<std::string>(), r["given"].as<std::string>(), r["truth"].as<std::string>(), r["score"].as<double>()});
    for (const auto& m : a["maneuvers"])
      s.maneuvers.push_back({m["name"].as<std::string>(), m["start_s"].as<double>(), m["end_s"].as<double>(),
                             m["largest_force_n"].as<double>(), m["reached"].as<bool>()});
    s.duration_s = a["duration_s"].as<double>();
    s.largest_force_n = a["largest_force_n"].as<double>();
    s.comfort_limit_n = a["comfort_limit_n"].as<double>();
    s.comfort_limit_source = a["comfort_limit_source"].as<std::string>();
    s.time_over_limit_s = a["time_over_limit_s"].as<double>();
    s.covered_share = a["covered_share"].as<double>();
  } catch (const std::exception& e) {
    throw std::runtime_error(file.string() + ": not an exercise's assessment (" + e.what() + ")");
  }
  return s;
}

// The scene the take recorded; none where it cannot be read (a scene whose trajectory files are
// gone still has a take worth seeing).
std::optional<config::Scene> recorded_scene(const RecordingHeader& header) {
  try {
    return config::parse_scene(header.scene_text, header.scene_path, fs::path(header.scene_path).parent_path()).scene;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// The probes' radii from the recorded scene (5 mm where it has none or cannot be read).
std::vector<double> recorded_radii(const RecordingHeader& header, const std::optional<config::Scene>& scene) {
  std::vector<double> radii(header.probes.size(), 5e-3);
  if (scene)
    for (std::size_t p = 0; p < radii.size(); ++p)
      for (const config::Probe& probe : scene->probes)
        if (probe.name == header.probes[p]) radii[p] = probe.radius_m;
  return radii;
}

// The smooth surfaces the trainer drew over the take's anatomy (label_surfaces.h), made again from
// the recorded scene; none where it has none or its volume cannot be read.
std::vector<LabelSurface> recorded_surfaces(const std::optional<config::Scene>& scene, const MeshView& anatomy) {
  try {
    if (scene)
      if (const auto labels = scene_label_map(*scene)) return label_surfaces(*labels, scene->mesh.meshing.regions, anatomy);
  } catch (const std::exception&) {
  }
  return {};
}

// The take's forces against time, a line per probe, the maneuvers' boundaries, the comfort limit,
// and the time shown.
class TakePlot : public QWidget {
 public:
  TakePlot(const ReviewTake& take, QWidget* parent) : QWidget(parent), take_(take) {
    setMinimumHeight(150);
    for (const RecordedDevice& d : take.recording.devices)
      for (const DeviceSample& s : d.samples) top_ = std::max(top_, s.force.norm());
    if (take.scores) top_ = std::max(top_, take.scores->comfort_limit_n);
    top_ = top_ > 0 ? 1.1 * top_ : 1;
  }
  void set_time(double t) {
    time_s_ = t;
    update();
  }

 protected:
  void paintEvent(QPaintEvent*) override {
    static const QColor kProbe[] = {QColor(80, 200, 120), QColor(90, 160, 240), QColor(240, 200, 80), QColor(220, 120, 220)};
    QPainter p(this);
    p.fillRect(rect(), QColor(24, 26, 32));
    const QRect area = rect().adjusted(44, 18, -8, -16);
    const double end = std::max(take_.duration_s, 1e-3);
    const auto x_of = [&](double t) { return area.left() + t / end * area.width(); };
    const auto y_of = [&](double f) { return area.bottom() - f / top_ * area.height(); };
    p.setPen(QColor(200, 200, 200));
    p.drawText(rect().adjusted(4, 2, 0, 0), Qt::AlignLeft | Qt::AlignTop, "force per probe over the take");
    p.drawText(QRect(0, area.top() - 6, 42, 14), Qt::AlignRight, QString::number(top_, 'g', 3));
    p.drawText(QRect(0, area.bottom() - 8, 42, 14), Qt::AlignRight, "0 N");
    p.setPen(QColor(70, 70, 80));
    p.drawRect(area);
    if (take_.scores) {
      p.setPen(QPen(QColor(120, 120, 140), 1, Qt::DashLine));
      for (std::size_t m = 0; m < take_.scores->maneuvers.size(); ++m) {
        const double x = x_of(take_.scores->maneuvers[m].start_s);
        if (m > 0) p.drawLine(QPointF(x, area.top()), QPointF(x, area.bottom()));
        p.drawText(QPointF(x + 3, area.top() + 12), QString::number(m + 1));
      }
      if (take_.scores->comfort_limit_n > 0) {
        p.setPen(QPen(QColor(220, 60, 60), 1, Qt::DashLine));
        const double y = y_of(take_.scores->comfort_limit_n);
        p.drawLine(QPointF(area.left(), y), QPointF(area.right(), y));
      }
    }
    for (std::size_t d = 0; d < take_.recording.devices.size(); ++d) {
      const auto& samples = take_.recording.devices[d].samples;
      QPainterPath line;
      // At most one point per pixel column (a take has a thousand samples a second).
      const std::size_t stride = std::max<std::size_t>(1, samples.size() / std::max(1, 2 * area.width()));
      for (std::size_t i = 0; i < samples.size(); i += stride) {
        const QPointF q(x_of(samples[i].time_s), y_of(samples[i].force.norm()));
        if (i == 0) line.moveTo(q);
        else line.lineTo(q);
      }
      p.setPen(QPen(kProbe[d % 4], 1.5));
      p.drawPath(line);
      p.drawText(QPointF(area.right() - 120, area.top() + 14 + 13 * d), QString::fromStdString(take_.recording.devices[d].name));
    }
    p.setPen(QPen(QColor(240, 240, 240), 1));
    p.drawLine(QPointF(x_of(time_s_), area.top()), QPointF(x_of(time_s_), area.bottom()));
  }

 private:
  const ReviewTake& take_;
  double top_ = 0, time_s_ = 0;
};

// Lines through the points, a polyline per run; point scalars when given.
vtkSmartPointer<vtkPolyData> polylines(const std::vector<std::vector<Eigen::Vector3d>>& runs, const std::vector<std::vector<double>>* values) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  auto scalars = vtkSmartPointer<vtkFloatArray>::New();
  scalars->SetName("force_n");
  for (std::size_t r = 0; r < runs.size(); ++r) {
    if (runs[r].size() < 2) continue;
    lines->InsertNextCell(static_cast<vtkIdType>(runs[r].size()));
    for (std::size_t i = 0; i < runs[r].size(); ++i) {
      lines->InsertCellPoint(points->InsertNextPoint(runs[r][i].data()));
      if (values) scalars->InsertNextValue(static_cast<float>((*values)[r][i]));
    }
  }
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  data->SetLines(lines);
  if (values) data->GetPointData()->SetScalars(scalars);
  return data;
}

}  // namespace

ReviewTake load_review_take(const fs::path& dir, const fs::path& recording) {
  if (!fs::is_directory(dir)) throw std::runtime_error(dir.string() + ": no such folder (a take's folder: OUT/exercise of `fetouch trainer --exercise`)");
  ReviewTake take;
  take.dir = dir;
  take.recording_file = recording.empty() ? dir / "take.h5" : recording.is_absolute() ? recording : dir / recording;
  take.anatomy_file = anatomy_beside(take.recording_file);
  if (!fs::exists(take.recording_file))
    throw std::runtime_error(take.recording_file.string() + ": no such recording (a take's folder has take.h5; --take names another)");
  if (!fs::exists(take.anatomy_file))
    throw std::runtime_error(take.anatomy_file.string() + ": no such file: the take's anatomy, which `fetouch trainer` writes beside "
                             "each take it records (takes recorded before 2026-11-28 have none)");
  take.recording = read_recording(take.recording_file);
  bool any = false;
  for (const RecordedDevice& d : take.recording.devices) {
    any = any || !d.samples.empty();
    if (!d.samples.empty()) take.duration_s = std::max(take.duration_s, d.samples.back().time_s);
  }
  if (!any) throw std::runtime_error(take.recording_file.string() + ": the recording has no probe samples: nothing to review");
  take.anatomy = read_tissue_vtu(take.anatomy_file);
  const std::optional<config::Scene> scene = recorded_scene(take.recording.header);
  take.probe_radii_m = recorded_radii(take.recording.header, scene);
  take.probe_radii_m.resize(take.recording.devices.size(), 5e-3);
  take.smooth = recorded_surfaces(scene, take.anatomy);
  if (fs::exists(dir / "assessment.json")) take.scores = read_scores(dir / "assessment.json");
  if (fs::exists(dir / "coverage.png")) take.coverage_png = dir / "coverage.png";
  return take;
}

ReviewWindow::ReviewWindow(ReviewTake take, const ReviewOptions& options) : take_(std::move(take)), options_(options) {
  setWindowTitle(QString::fromStdString("Fetouch review: " + take_.dir.string()));
  vtk_widget_ = new QVTKOpenGLNativeWidget(this);
  auto render_window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  vtk_widget_->setRenderWindow(render_window);
  render_window_ = render_window;
  render_window->SetMultiSamples(0);
  // The anatomy; over it the moves between presses; over those the presses (each layer drawn
  // whole over the one below, so a path is never hidden by the tissue or by a move above it).
  render_window->SetNumberOfLayers(3);
  auto base = vtkSmartPointer<vtkRenderer>::New(), travel = vtkSmartPointer<vtkRenderer>::New(), press = vtkSmartPointer<vtkRenderer>::New();
  travel->SetLayer(1), press->SetLayer(2);
  travel->SetActiveCamera(base->GetActiveCamera()), press->SetActiveCamera(base->GetActiveCamera());
  travel->InteractiveOff(), press->InteractiveOff();
  for (vtkRenderer* r : {base.Get(), travel.Get(), press.Get()}) render_window->AddRenderer(r);
  renderer_ = base, travel_layer_ = travel, press_layer_ = press;
  vtk_widget_->setMinimumSize(560, 480);
  view_ = std::make_unique<TissueView>(renderer_, take_.anatomy, take_.probe_radii_m, take_.smooth);
  view_->update_tissue(TissueSnapshot{}, ColourField::regions);  // at rest: the take records no tissue states
  build_paths();
  set_paths_visible(options_.paths);
  view_->reset_camera();
  if (take_.scores) {
    // An exercise's phantom, seen as its coverage map beside it shows the abdomen: from the front
    // (+z), the fundus (+x) up and the mother's right (+y) on the left.
    camera()->SetViewUp(1, 0, 0);
    camera()->OrthogonalizeViewUp();
    renderer_->ResetCameraClippingRange();
  }

  auto* side = new QWidget(this);
  auto* column = new QVBoxLayout(side);
  scores_ = new QLabel(side);
  scores_->setWordWrap(true);
  scores_->setTextFormat(Qt::RichText);
  scores_->setAlignment(Qt::AlignTop | Qt::AlignLeft);
  std::string text;
  char line[300];
  if (take_.scores) {
    const ReviewScores& s = *take_.scores;
    text = "<b>The fetus: " + s.pose + "</b><br>";
    for (const auto& a : s.answers)
      text += a.asked + ": " + (a.given.empty() ? "(none)" : a.given) + (a.score == 1 ? " (right)" : a.score > 0 ? " (nearly)" : " (wrong: " + a.truth + ")") + "<br>";
    text += "<br>";
    for (std::size_t m = 0; m < s.maneuvers.size(); ++m) {
      std::snprintf(line, sizeof line, "%zu. %s, %.1f-%.1f s, %.2f N: %s<br>", m + 1, s.maneuvers[m].name.c_str(), s.maneuvers[m].start_s,
                    s.maneuvers[m].end_s, s.maneuvers[m].largest_force_n, s.maneuvers[m].reached ? "reached" : "<b>not reached</b>");
      text += line;
    }
    std::snprintf(line, sizeof line, "<br>Time %.1f s. Largest force %.2f N", s.duration_s, s.largest_force_n);
    text += line;
    if (s.comfort_limit_n > 0) {
      std::snprintf(line, sizeof line, " (limit %.2f N: %.2f s above it)", s.comfort_limit_n, s.time_over_limit_s);
      text += line;
    }
    std::snprintf(line, sizeof line, ". Abdomen covered: %.0f %%.", 100 * s.covered_share);
    text += line;
  } else {
    std::snprintf(line, sizeof line, "<b>A take of %.1f s</b> (not an exercise's: no scores).", take_.duration_s);
    text = line;
  }
  scores_->setText(QString::fromStdString(text));
  column->addWidget(scores_, 2);
  if (!take_.coverage_png.empty()) {
    coverage_ = new QLabel(side);
    coverage_->setAlignment(Qt::AlignCenter);
    QPixmap picture(QString::fromStdString(take_.coverage_png.string()));
    coverage_->setPixmap(picture.scaledToHeight(std::min(picture.height(), 240), Qt::SmoothTransformation));
    coverage_->setToolTip("the coverage map: the abdomen from the front, the fundus at the top, the mother's right on the left");
    column->addWidget(coverage_, 2);
  }
  auto* plot = new TakePlot(take_, side);
  plot_ = plot;
  column->addWidget(plot, 1);

  auto* split = new QSplitter(this);
  split->addWidget(vtk_widget_);
  split->addWidget(side);
  split->setStretchFactor(0, 3), split->setStretchFactor(1, 2);
  setCentralWidget(split);

  QToolBar* bar = addToolBar("time");
  play_ = new QPushButton("Play (space)", this);
  play_->setShortcut(QKeySequence(Qt::Key_Space));
  connect(play_, &QPushButton::clicked, this, [this] { toggle_play(); });
  bar->addWidget(play_);
  slider_ = new QSlider(Qt::Horizontal, this);
  slider_->setRange(0, static_cast<int>(std::lround(1e3 * take_.duration_s)));  // ms
  slider_->setMinimumWidth(600);
  slider_->setSingleStep(100), slider_->setPageStep(1000);  // arrows 0.1 s, page keys 1 s
  connect(slider_, &QSlider::valueChanged, this, [this](int ms) {
    if (std::lround(1e3 * time_s_) != ms) show_time(1e-3 * ms);
  });
  bar->addWidget(slider_);
  auto* paths = new QPushButton("Paths (P)", this);
  paths->setCheckable(true);
  paths->setChecked(options_.paths);
  paths->setShortcut(QKeySequence(Qt::Key_P));
  connect(paths, &QPushButton::toggled, this, [this](bool on) { set_paths_visible(on); });
  bar->addWidget(paths);
  time_label_ = new QLabel(this);
  statusBar()->addWidget(time_label_, 1);
  player_ = new QTimer(this);
  connect(player_, &QTimer::timeout, this, [this] { step_play(); });
  resize(1280, 800);
  show_time(options_.at_s < 0 ? take_.duration_s : options_.at_s);
}

ReviewWindow::~ReviewWindow() {
  if (player_) player_->stop();
}

void ReviewWindow::build_paths() {
  double largest = 0;
  for (const RecordedDevice& d : take_.recording.devices)
    for (const DeviceSample& s : d.samples)
      if (s.in_contact) largest = std::max(largest, s.force.norm());
  // Red at the comfort limit when one is stated and the take stayed under it, else at the take's largest force.
  force_range_n_ = std::max({largest, take_.scores ? take_.scores->comfort_limit_n : 0.0, 0.1});
  auto lookup = vtkSmartPointer<vtkLookupTable>::New();
  lookup->SetHueRange(0.33, 0.0);  // green to red
  lookup->SetTableRange(0, force_range_n_);
  lookup->Build();
  for (const RecordedDevice& d : take_.recording.devices) {
    // Runs in contact (the force's magnitude at each point) and between them; every 5th tick (5 ms).
    std::vector<std::vector<Eigen::Vector3d>> pressing, moving;
    std::vector<std::vector<double>> forces;
    bool was = false;
    for (std::size_t i = 0; i < d.samples.size(); i += 5) {
      const DeviceSample& s = d.samples[i];
      if (i == 0 || s.in_contact != was) {
        // Each run starts where the last ended, so the path has no gaps.
        const Eigen::Vector3d joint = i == 0 ? s.position : d.samples[i - 5].position;
        if (s.in_contact) pressing.push_back({joint}), forces.push_back({d.samples[i - (i == 0 ? 0 : 5)].force.norm()});
        else moving.push_back({joint});
        was = s.in_contact;
      }
      if (s.in_contact) pressing.back().push_back(s.position), forces.back().push_back(s.force.norm());
      else moving.back().push_back(s.position);
    }
    auto press = vtkSmartPointer<vtkPolyDataMapper>::New();
    press->SetInputData(polylines(pressing, &forces));
    press->SetLookupTable(lookup);
    press->SetScalarRange(0, force_range_n_);
    press->SetScalarModeToUsePointData();
    auto press_actor = vtkSmartPointer<vtkActor>::New();
    press_actor->SetMapper(press);
    press_actor->GetProperty()->SetLineWidth(4);
    press_actor->GetProperty()->LightingOff();
    press_layer_->AddActor(press_actor);
    auto move = vtkSmartPointer<vtkPolyDataMapper>::New();
    move->SetInputData(polylines(moving, nullptr));
    move->ScalarVisibilityOff();
    auto move_actor = vtkSmartPointer<vtkActor>::New();
    move_actor->SetMapper(move);
    move_actor->GetProperty()->SetColor(0.75, 0.75, 0.78);
    move_actor->GetProperty()->SetLineWidth(1.5);
    move_actor->GetProperty()->LightingOff();
    travel_layer_->AddActor(move_actor);
    path_actors_.push_back(press_actor), path_actors_.push_back(move_actor);
  }
  auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
  bar->SetLookupTable(lookup);
  bar->SetTitle("force (N)");
  bar->SetNumberOfLabels(4);
  bar->SetWidth(0.08), bar->SetHeight(0.45);
  bar->SetPosition(0.02, 0.05);
  bar->GetTitleTextProperty()->SetFontSize(12);
  press_layer_->AddActor2D(bar);
  bar_ = bar;
}

void ReviewWindow::set_paths_visible(bool on) {
  for (vtkActor* a : path_actors_)
    a->SetVisibility(on);
  if (bar_) bar_->SetVisibility(on);
  options_.paths = on;
  if (render_window_) render_window_->Render();
}

std::size_t ReviewWindow::sample_at(std::size_t device, double t_s) const {
  const auto& samples = take_.recording.devices[device].samples;
  const auto at = std::lower_bound(samples.begin(), samples.end(), t_s, [](const DeviceSample& s, double t) { return s.time_s < t; });
  return at == samples.end() ? samples.size() - 1 : static_cast<std::size_t>(at - samples.begin());
}

int ReviewWindow::maneuver_at(double t_s) const {
  if (!take_.scores) return -1;
  const auto& m = take_.scores->maneuvers;
  for (int k = static_cast<int>(m.size()) - 1; k >= 0; --k)
    if (t_s >= m[k].start_s) return k;
  return m.empty() ? -1 : 0;
}

void ReviewWindow::show_time(double t_s) {
  time_s_ = std::clamp(t_s, 0.0, take_.duration_s);
  std::array<SessionMonitor::ProbeTick, SessionMonitor::kMaxDevices> ticks{};
  const int count = static_cast<int>(std::min<std::size_t>(take_.recording.devices.size(), SessionMonitor::kMaxDevices));
  std::string text;
  char line[200];
  std::snprintf(line, sizeof line, "t = %.3f s of %.3f", time_s_, take_.duration_s);
  text = line;
  if (const int m = maneuver_at(time_s_); m >= 0) text += "  ·  maneuver " + std::to_string(m + 1) + ": " + take_.scores->maneuvers[m].name;
  for (int d = 0; d < count; ++d) {
    if (take_.recording.devices[d].samples.empty()) continue;
    const DeviceSample& s = take_.recording.devices[d].samples[sample_at(d, time_s_)];
    ticks[d].position = s.position, ticks[d].proxy = s.proxy, ticks[d].force = s.force, ticks[d].in_contact = s.in_contact;
    std::snprintf(line, sizeof line, "  ·  %s %.2f N%s", take_.recording.devices[d].name.c_str(), s.force.norm(), s.in_contact ? " pressing" : "");
    text += line;
  }
  view_->update_probes(ticks, count);
  time_label_->setText(QString::fromStdString(text));
  static_cast<TakePlot*>(plot_)->set_time(time_s_);
  {
    const QSignalBlocker quiet(slider_);
    slider_->setValue(static_cast<int>(std::lround(1e3 * time_s_)));
  }
  render_window_->Render();
}

void ReviewWindow::toggle_play() {
  if (player_->isActive()) {
    player_->stop();
    play_->setText("Play (space)");
    return;
  }
  if (time_s_ >= take_.duration_s) show_time(0);
  play_from_ = std::chrono::steady_clock::now();
  play_from_s_ = time_s_;
  play_->setText("Pause (space)");
  player_->start(40);
}

void ReviewWindow::step_play() {
  const double t = play_from_s_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - play_from_).count();
  show_time(t);
  if (t >= take_.duration_s) toggle_play();
}

bool ReviewWindow::save_screenshot(const fs::path& file) {
  render_window_->Render();
  std::error_code ignored;
  if (file.has_parent_path()) fs::create_directories(file.parent_path(), ignored);
  return grab().save(QString::fromStdString(file.string()));
}

vtkCamera* ReviewWindow::camera() const { return renderer_->GetActiveCamera(); }

ReviewWindow::Rect ReviewWindow::view_rect() const {
  const QPoint corner = vtk_widget_->mapTo(this, QPoint(0, 0));
  const qreal scale = devicePixelRatioF();
  return {static_cast<int>(std::lround(corner.x() * scale)), static_cast<int>(std::lround(corner.y() * scale)),
          static_cast<int>(std::lround(vtk_widget_->width() * scale)), static_cast<int>(std::lround(vtk_widget_->height() * scale))};
}

}  // namespace fetouch::app::trainer
