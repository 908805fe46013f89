#include "app/trainer/trainer_session.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "app/build_info.h"
#include "app/log.h"
#include "app/recording.h"
#include "app/scene_devices.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "fem/fem_environment.h"
#include "fem/tissue_model.h"
#include "haptics/phantom.h"

namespace fetouch::app::trainer {

namespace {

// The mouse's hand: light and critically damped (a mouse moves in jumps; the probe should follow
// without ringing), 200 N/m so that a 1 N press lags the cursor by 5 mm.
constexpr haptics::HandParameters kMouseHand{0.1, 200, 9};

// Above the tissue's highest point, in the middle of its footprint: where a mouse probe starts.
Eigen::Vector3d above_the_tissue(const MeshView& mesh) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = Eigen::Vector3d::Constant(-1e300);
  for (const auto& t : mesh.boundary_triangles)
    for (unsigned int v : t) {
      const Eigen::Vector3d p(mesh.points[v][0], mesh.points[v][1], mesh.points[v][2]);
      low = low.cwiseMin(p), high = high.cwiseMax(p);
    }
  return {0.5 * (low.x() + high.x()), 0.5 * (low.y() + high.y()), high.z() + 0.01};
}

// Each probe's contact patch as it is now (deformed): its centre and normal.
void patches(const fem::QuasiStaticSolver& solver, int probes, TissueSnapshot& s) {
  s.patch_centre.resize(probes), s.patch_normal.resize(probes);
  for (int p = 0; p < probes; ++p) {
    const dealii::Point<3> c = solver.patch_center(p);
    const dealii::Tensor<1, 3> n = solver.patch_normal(p);
    s.patch_centre[p] = {c[0], c[1], c[2]}, s.patch_normal[p] = {n[0], n[1], n[2]};
  }
}

}  // namespace

TrainerSession::TrainerSession(const config::Scene& scene, const TrainerOptions& options, std::vector<std::string>& messages)
    : scene_(scene) {
  scene_.mesh = mesh_scene_volume(scene_);
  settings_.loop = loop_settings(scene_);
  settings_.loop.modes = &modes_;
  model_ = build_session_tissue(scene_);
  fem::TissueModel* model = model_.get();
  fem::QuasiStaticSolver& solver = *model->solver;
  {
    fem::QuasiStaticSolver::DrawingMesh d = solver.drawing_mesh();
    mesh_.points = std::move(d.points), mesh_.tetrahedra = std::move(d.tetrahedra);
    mesh_.tetrahedron_cell = std::move(d.tetrahedron_cell), mesh_.material = std::move(d.material);
    mesh_.boundary_triangles = std::move(d.boundary_triangles);
    mesh_.boundary_triangle_cell = std::move(d.boundary_triangle_cell);
    mesh_.cells = solver.cells();
    for (const auto& region : model->mesh.regions)
      mesh_.region_name[region.material_id] = region.name.empty() ? "region " + std::to_string(region.material_id) : region.name;
  }
  // The devices, and where each one's contact patch starts.
  long ticks = -1;
  cursors_.assign(scene_.probes.size(), nullptr);
  for (int p = 0; p < static_cast<int>(scene_.probes.size()); ++p) {
    const config::Probe& probe = scene_.probes[p];
    std::optional<haptics::Trajectory> path;
    bool mouse = probe.device.type == config::DeviceType::mouse || (p == 0 && options.mouse);
    Eigen::Vector3d start = above_the_tissue(mesh_);
    if (!mouse && probe.device.type == config::DeviceType::phantom) {
      try {
        devices_.push_back(make_device(probe, scene_, settings_.loop, nullptr));
        start = dynamic_cast<haptics::PhantomDevice&>(*devices_.back()).position_now();
      } catch (const std::exception& e) {
        mouse = true;
        if (cursor_probe_ < 0) {
          messages.push_back(std::string(e.what()) + "; the mouse drives probe " + probe.name + " instead");
        } else {
          // The mouse drives another probe first: this one waits 4 cm to the side, above the tissue.
          messages.push_back(std::string(e.what()) + "; the mouse drives probe " + probe.name + " too (Tab: the next hand)");
          start += Eigen::Vector3d(0, 0.04 * (p % 2 ? 1 : -1), 0);
        }
      }
    } else if (!mouse) {
      const std::filesystem::path file = (p == 0 && options.trajectory) ? *options.trajectory : probe.device.trajectory;
      if (file.empty()) throw std::runtime_error("probe " + probe.name + " has no trajectory (device.trajectory)");
      path = read_probe_trajectory(file, probe.name, p);
      start = path->positions_m.front();
      devices_.push_back(make_device(probe, scene_, settings_.loop, &*path));
      ticks = std::max(ticks, devices_.back()->ticks());
    }
    if (options.lockstep && (mouse || probe.device.type == config::DeviceType::phantom))
      throw std::runtime_error("probe " + probe.name + ": lockstep (--clock lockstep) needs every probe scripted, and this one is " +
                               (mouse ? "the mouse's" : "a PHANTOM") + "; give it a trajectory (type: replay or operator)");
    if (mouse) {
      auto cursor = std::make_unique<haptics::CursorOperator>(start, kMouseHand, settings_.loop.period_s);
      cursors_[p] = cursor.get();
      if (cursor_probe_ < 0) cursor_probe_ = p;
      devices_.push_back(std::move(cursor));
    }
    const dealii::Point<3> touch = solver.boundary_point_nearest(dealii::Point<3>(start[0], start[1], start[2]));
    solver.add_contact_patch(touch, probe.radius_m);
    settings_.probes.push_back(probe.name);
  }
  // How long: the duration asked for, else until the scripted devices end, else (a mouse or a
  // PHANTOM, which never end) the cap.
  const double rate = scene_.haptics.rate_hz;
  if (options.duration_s > 0)
    settings_.max_ticks = std::lround(options.duration_s * rate);
  else if (cursor_probe_ >= 0 || ticks < 0)
    settings_.max_ticks = std::lround(options.max_minutes * 60 * rate);
  auto environment = std::make_unique<fem::FemEnvironment>(std::move(model->solver), model->newton);
  fem::FemEnvironment& fem = *environment;
  environment_ = std::move(environment);
  lockstep_ = options.lockstep;
  if (!lockstep_) {  // lockstep keeps the solver as `fetouch replay` runs it: reproducible
    fem.solver().set_assembly_threads(realtime_solver_cores(settings_) >= 2 ? 2 : 1);
    fem.solver().set_deterministic_factorisations(false);
  }
  if (options.recording) {
    settings_.recording = *options.recording;
    settings_.header.program_version = std::string("fetouch ") + kVersion + " (" + kGitRevision + ")";
    settings_.header.scene_path = scene_.source.string();
    settings_.header.scene_text = scene_.text;
    settings_.header.local_model = config::to_string(scene_.haptics.local_model);
    settings_.header.hold = config::to_string(scene_.haptics.hold);
  }
  settings_.monitor = &monitor_;
  settings_.stop = &stop_;
  settings_.pause = &pause_;
  // Each frame's answer, for the window: copied in the solver thread (after the answer went to the
  // haptic loop, so the copy never delays a force).
  const int probes = static_cast<int>(scene_.probes.size());
  settings_.after_frame = [this, &fem, probes](const FrameRecord& f) {
    TissueSnapshot& s = snapshots_.back();
    s.frame = f.frame, s.time_s = f.time_s, s.solve_s = f.solve_s, s.newton_iterations = f.newton_iterations;
    s.stability_margin = f.stability_margin, s.proportional_gain = f.proportional_gain, s.integral_gain = f.integral_gain;
    fem.solver().vertex_displacements(s.displacement);
    if (want_stress_.load(std::memory_order_relaxed)) {
      const std::vector<double> stress = fem.solver().cell_fields().von_mises;
      s.von_mises.assign(stress.begin(), stress.end());
    } else {
      s.von_mises.clear();
    }
    patches(fem.solver(), probes, s);
    snapshots_.publish();
  };
  // At rest, before the first frame.
  TissueSnapshot& rest = snapshots_.back();
  fem.solver().vertex_displacements(rest.displacement);
  patches(fem.solver(), probes, rest);
  snapshots_.publish();
}

TrainerSession::~TrainerSession() {
  stop_ = true;
  pause_ = false;
  if (thread_.joinable()) thread_.join();
}

void TrainerSession::start() {
  if (thread_.joinable()) return;
  running_ = true;
  thread_ = std::thread([this] {
    try {
      SessionSummary s = lockstep_ ? run_lockstep(*environment_, devices_, settings_) : run_realtime(*environment_, devices_, settings_);
      std::lock_guard<std::mutex> lock(result_mutex_);
      summary_ = std::move(s);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(result_mutex_);
      error_ = e.what();
    }
    running_ = false;
  });
}

int TrainerSession::mouse_probes() const {
  return static_cast<int>(std::count_if(cursors_.begin(), cursors_.end(), [](const auto* c) { return c != nullptr; }));
}

bool TrainerSession::switch_cursor() {
  if (mouse_probes() < 2) return false;
  const int n = static_cast<int>(cursors_.size());
  for (int k = 1; k < n; ++k)
    if (cursors_[(cursor_probe_ + k) % n]) {
      cursor_probe_ = (cursor_probe_ + k) % n;
      return true;
    }
  return false;
}

void TrainerSession::wait() {
  if (thread_.joinable()) thread_.join();
}

std::string TrainerSession::error() const {
  std::lock_guard<std::mutex> lock(result_mutex_);
  return error_;
}

SessionSummary TrainerSession::summary() const {
  std::lock_guard<std::mutex> lock(result_mutex_);
  return summary_;
}

}  // namespace fetouch::app::trainer
