// The trainer's session (docs/trainer.md): the real-time session of `fetouch run` / `replay --clock
// realtime` (app/session.h) on its own thread, with what a window needs to show it and drive it.
// No Qt here: the window (trainer_window.h) only reads this class's lock-free hand-overs.
//   - the tissue: after each solver frame the solver thread copies the vertex displacements (and,
//     when asked, the per-cell von Mises stress) into a triple buffer; the window takes the newest;
//   - the probes: every tick, through SessionMonitor::probes (device point, proxy, force);
//   - mouse probes: a CursorOperator (haptics/devices.h) per probe the mouse drives; the window
//     moves its target;
//   - switches of local model and hold, through a haptics::ModeChannel the loop's producer answers;
//   - pause (no tick runs: simulated time stands still) and stop (forces ramp out over 0.2 s).
// A session is one take: reset and record start a new one (the window builds another).
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/session.h"
#include "config/scene.h"
#include "haptics/devices.h"
#include "haptics/lock_free.h"

namespace fetouch::fem {
struct TissueModel;
}

namespace fetouch::app::trainer {

struct TissueSnapshot {
  long frame = -1;          // the frame whose answer this is (-1: at rest)
  double time_s = 0;        // simulated time of the answer
  double solve_s = 0, stability_margin = 1, proportional_gain = 0, integral_gain = 0;
  int newton_iterations = 0;
  std::vector<float> displacement;  // 3 per mesh point, m
  std::vector<float> von_mises;     // per cell, Pa (empty unless asked for)
  std::vector<Eigen::Vector3d> patch_centre, patch_normal;  // per probe, deformed
};

struct TrainerOptions {
  std::optional<std::filesystem::path> trajectory;  // the first probe's, instead of the scene's
  bool mouse = false;                                // the mouse drives the first probe
  double duration_s = 0;                             // 0: until stopped (at most max_minutes)
  double max_minutes = 30;
  std::optional<std::filesystem::path> recording;   // the HDF5 recording of this take
  // Simulated time (app/session.h's lockstep): every frame answered before the next, the take as
  // fast as the solver goes and the same, bit for bit, every time. Scripted probes only (tests,
  // demonstrations); a mouse or a PHANTOM needs real time.
  bool lockstep = false;
};

struct MeshView {
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<unsigned int, 4>> tetrahedra;
  std::vector<unsigned int> tetrahedron_cell, material;
  std::vector<std::array<unsigned int, 3>> boundary_triangles;
  std::vector<unsigned int> boundary_triangle_cell;
  unsigned int cells = 0;
  std::map<unsigned int, std::string> region_name;  // by material id (empty names: "region N")
};

class TrainerSession {
 public:
  // Builds the tissue and the devices (seconds: the mesh is cached, the tangent factorised).
  // Throws std::runtime_error naming what failed. `messages` receives what the user should know
  // (a PHANTOM not found and the mouse used instead).
  TrainerSession(const config::Scene& scene, const TrainerOptions& options, std::vector<std::string>& messages);
  ~TrainerSession();  // stops the session and joins its thread

  void start();
  void request_stop() { stop_ = true; }
  void set_paused(bool paused) { pause_ = paused; }
  bool paused() const { return pause_.load(); }
  bool running() const { return running_.load(); }
  // After the session ended: its summary, or the error that ended it (empty: none).
  std::string error() const;
  SessionSummary summary() const;
  void wait();

  const MeshView& mesh() const { return mesh_; }
  const config::Scene& scene() const { return scene_; }
  const haptics::HapticLoopSettings& loop() const { return settings_.loop; }
  // A switch of local model and hold: analysed by the solver thread on its next frame's stiffness,
  // applied at the frame after if the analysis accepts it (haptics/mode_channel.h).
  long ask_mode(haptics::LocalModelKind model, haptics::HoldKind hold) { return modes_.ask(model, hold); }
  haptics::ModeVerdict mode_verdict() const { return modes_.verdict(); }
  // The newest tissue state, when one came since the last call (the window's thread only).
  bool take_snapshot() { return snapshots_.take(); }
  const TissueSnapshot& snapshot() const { return snapshots_.front(); }
  void want_stress(bool on) { want_stress_ = on; }
  SessionMonitor& monitor() { return monitor_; }
  // The probe the mouse drives now (nullptr when none does): the window sets its target. Every
  // `type: mouse` probe, and every PHANTOM not found, is the mouse's; it drives one at a time, and
  // the others hold where it left them (a steadying hand) until switch_cursor() comes to them.
  haptics::CursorOperator* cursor() { return cursor_probe_ < 0 ? nullptr : cursors_[cursor_probe_]; }
  int cursor_probe() const { return cursor_probe_; }
  haptics::CursorOperator* cursor_of(int probe) {
    return probe >= 0 && probe < static_cast<int>(cursors_.size()) ? cursors_[probe] : nullptr;
  }
  int mouse_probes() const;
  // The mouse on to the next of its probes (in the scene's order, round); false when it has one or none.
  bool switch_cursor();
  const std::vector<std::string>& probe_names() const { return settings_.probes; }
  double solver_period_s() const { return settings_.loop.period_s * settings_.loop.ratio; }

 private:
  config::Scene scene_;
  SessionSettings settings_;
  SessionMonitor monitor_;
  haptics::ModeChannel modes_;
  std::unique_ptr<fem::TissueModel> model_;  // its mesh and materials, which the solver refers to
  std::unique_ptr<haptics::Environment> environment_;
  std::vector<std::unique_ptr<haptics::Device>> devices_;
  std::vector<haptics::CursorOperator*> cursors_;  // per probe: its cursor, or null (held in devices_)
  int cursor_probe_ = -1;
  MeshView mesh_;
  haptics::TripleBuffer<TissueSnapshot> snapshots_{TissueSnapshot{}};
  std::atomic<bool> stop_{false}, pause_{false}, running_{false}, want_stress_{false};
  bool lockstep_ = false;
  std::thread thread_;
  mutable std::mutex result_mutex_;
  SessionSummary summary_;
  std::string error_;
};

}  // namespace fetouch::app::trainer
