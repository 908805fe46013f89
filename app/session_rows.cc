#include "app/session_rows.h"

#include <Eigen/Eigenvalues>

namespace fetouch::app {

// /frames/mode's codes (docs/replay.md) are the enumerators' values.
static_assert(static_cast<int>(haptics::LocalModelKind::p) == 0 && static_cast<int>(haptics::LocalModelKind::pi) == 1 &&
              static_cast<int>(haptics::LocalModelKind::smith) == 2 && static_cast<int>(haptics::LocalModelKind::pi_smith) == 3 &&
              static_cast<int>(haptics::HoldKind::zoh) == 0 && static_cast<int>(haptics::HoldKind::foh) == 1);

// The frame's row of the recording: the solve's status, the eigenvalues of the condensed normal
// stiffness W_n^-1, the gains chosen for it and the mode they are for.
FrameRecord frame_record(const haptics::FrameSlot& slot, double time_s) {
  FrameRecord f;
  f.frame = slot.update.frame;
  f.time_s = time_s;
  f.solve_s = slot.update.status.seconds;
  f.residual = slot.update.status.residual;
  f.newton_iterations = slot.update.status.iterations;
  f.converged = slot.update.status.converged;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(slot.normal_compliance);
  for (int i = static_cast<int>(eigen.eigenvalues().size()) - 1; i >= 0; --i)
    f.stiffness_eigenvalues.push_back(eigen.eigenvalues()[i] > 0 ? 1 / eigen.eigenvalues()[i] : 0);
  f.proportional_gain = slot.gains.proportional;
  f.integral_gain = slot.gains.integral;
  f.local_model = static_cast<int>(slot.local_model);
  f.hold = static_cast<int>(slot.hold);
  f.stability_margin = 1 - slot.selection.spectral_radius;
  return f;
}

void add_energy_audit(FrameRecord& record, long frame, const std::vector<haptics::FrameEnergy>& energy) {
  record.energy_frame = frame;
  record.hand_energy_j.clear(), record.tissue_work_j.clear(), record.held_energy_j.clear(), record.generated_energy_j.clear();
  for (const haptics::FrameEnergy& e : energy) {
    record.hand_energy_j.push_back(e.hand_j);
    record.tissue_work_j.push_back(e.tissue_j);
    record.held_energy_j.push_back(e.held_j);
    record.generated_energy_j.push_back(e.generated_j);
  }
}

// The passivity layer's counters at the end of a session.
std::vector<PassivitySummary> passivity_summary(const haptics::HapticLoop& loop) {
  std::vector<PassivitySummary> out;
  for (int c = 0; c < loop.contacts(); ++c) {
    const haptics::PassivityPort& p = loop.passivity(c);
    PassivitySummary s;
    s.generation_events = static_cast<long>(p.generation_events());
    s.generating_ticks = static_cast<long>(p.generating_ticks());
    s.controller_ticks = static_cast<long>(p.controller_ticks());
    s.adjusting_ticks = static_cast<long>(p.adjusting_ticks());
    s.max_controller_force_n = p.max_controller_force_n();
    s.min_energy_j = p.min_energy_j();
    s.min_scale = p.min_scale();
    s.generating_frames = loop.generating_frames(c);
    s.max_frame_generation_j = loop.max_generated_j(c);
    out.push_back(s);
  }
  return out;
}

std::vector<IdentificationSummary> identification_summary(const haptics::HapticLoop& loop) {
  std::vector<IdentificationSummary> out;
  const double frame_s = loop.settings().ratio * loop.settings().period_s;
  for (int c = 0; c < loop.contacts(); ++c) {
    const haptics::IdentificationCheck& check = loop.identification(c);
    IdentificationSummary s;
    s.frames_compared = check.frames_compared;
    s.disagreements = check.disagreements;
    s.first_disagreement_s = check.first_disagreement_frame < 0 ? -1.0 : check.first_disagreement_frame * frame_s;
    s.max_relative_difference = check.max_relative_difference;
    s.last_relative_difference = check.last_relative_difference;
    out.push_back(s);
  }
  return out;
}

void publish_tick(SessionMonitor& monitor, long ticks_done, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<haptics::ContactOutput>& out, const DeviceSample* sent, int m) noexcept {
  auto& probes = monitor.probes.back();
  for (int d = 0; d < m && d < SessionMonitor::kMaxDevices; ++d) {
    monitor.force_n[d].store(sent[d].force.norm(), std::memory_order_relaxed);
    probes[d] = {points[d],
                 out[d].proxy,
                 sent[d].force,
                 out[d].penetration,
                 out[d].in_contact,
                 out[d].port_energy_j,
                 out[d].passivity_scale,
                 out[d].identified ? out[d].identified_stiffness_n_per_m : 0.0,
                 out[d].condensed_stiffness_n_per_m};
  }
  monitor.probes.publish();
  monitor.ticks.store(ticks_done, std::memory_order_relaxed);
}


}  // namespace fetouch::app
