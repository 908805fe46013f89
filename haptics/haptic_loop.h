// The haptic loop in 3D for m contacts: what runs every tick at 1 kHz, between device and tissue.
//
// Per tick k = jN + i (ARCHITECTURE.md section 3; in normal coordinates: normal_loop.h):
//   1. at i == 0, if an update was published during frame j - 1, it becomes the newest held one
//      (the previous newest moves back) and its gains start blending in;
//   2. hold: ZOH uses the newest update's contact frames; FOH interpolates the two newest (an
//      answer that comes late, in real time, is held at the newest and pauses the integrator);
//   3. geometry: each device point's penetration e_c behind the held surface along its normal
//      (contact_frame.h), and the reference force of the Smith predictor, held the same way;
//   4. the local model on the m penetrations in normal coordinates, with the compliance projected
//      on the normals, W_n = N' W N (N = blockdiag(n_c)); unilateral: F_c >= 0, reset on release;
//   5. force F_c n_c on device c through its PassivityPort (passivity.h: the energy at the port
//      the device sees, and the stiffness scaled down when the loop with the hand in it hands the
//      hand energy), then its ForceSafety (finite, watchdog, a stopping session's ramp out, clamp,
//      rate limit): the one chain that shapes the force, which a device only maps to its own
//      frame and units (and a PHANTOM cuts for its own errors and clutch); the proxy is the
//      device point moved along n_c onto the held (or predicted) surface;
//   6. at i == 0 the samples (device point, force -F_c n_c on the tissue) are decimated for the
//      environment; its answer is published before the next frame starts.
//
// The producer side (prepare + publish: the solver thread at run time, the lockstep session here)
// projects the new compliance on the normals and, with gain scheduling on, re-selects the gains
// robustly (gain_selection.h), warm-started from the gains in use. A switch of local model and hold
// asked through settings.modes is analysed there too, on the frame's stiffness: accepted only if
// gains robustly stable for it exist (scheduling on) or the given gains are (off); the slot then
// carries the new mode, which the tick applies at the frame's first tick with its gains at once
// (no blend between two models; an integrator starts from zero, and one dropped takes its share
// of the force with it: the safety layer's rate limit spreads that step). tick() itself never allocates,
// locks, throws or waits; it swaps slot indices, never copies an update.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

#include "haptics/environment.h"
#include "haptics/force_safety.h"
#include "haptics/gain_selection.h"
#include "haptics/hold.h"
#include "haptics/identification.h"
#include "haptics/local_model.h"
#include "haptics/lock_free.h"
#include "haptics/mode_channel.h"
#include "haptics/passivity.h"

namespace fetouch::haptics {

struct HapticLoopSettings {
  LocalModelKind local_model = LocalModelKind::pi;
  HoldKind hold = HoldKind::foh;
  int ratio = 50;                 // N ticks per solver frame
  double period_s = 1e-3;         // T
  LocalModelGains gains;          // used as given when scheduling is off; the first guess otherwise
  bool schedule_gains = true;     // re-select the gains for every update's stiffness
  GainSelectionOptions selection;
  int blend_ticks = 20;           // a gain change is spread over this many ticks
  // The coupling between contacts in the local model: off, W_n is cut to its diagonal (the Smith
  // predictor and the gain selection see each contact alone). The environment still answers with
  // the coupled tissue, so the contacts then feel each other only through its frames.
  bool coupling = true;
  double integrator_limit_n = 1e300;
  // A contact pushes and never pulls (F >= 0, the integrator reset on release): what devices run.
  // False holds the contact on both sides, the loop's linearisation about a contact never lost:
  // what the lifting (stability_analysis.h) analyses, on NormalLoop (normal_loop.h).
  bool unilateral = true;
  ForceSafetyLimits safety;
  // The passivity layer per contact; its period is the loop's (period_s), whatever it says.
  PassivitySettings passivity;
  // On-line identification per contact (identification.h), compared at every frame's first tick
  // with the stiffness the newest frame condensed: a relative difference over
  // identification_bound is a disagreement (counted per contact).
  IdentificationSettings identification;
  double identification_bound = 0.25;
  // The energy audit (FrameEnergy): a frame that generated more than this is counted.
  double audit_tolerance_j = 1e-6;
  // Switches of local model and hold asked while running (mode_channel.h); none: the mode stays.
  ModeChannel* modes = nullptr;
};

// One update as the loop holds it: the environment's answer plus what the producer derived.
struct FrameSlot {
  EnvironmentUpdate update;
  Eigen::MatrixXd normal_compliance;  // W_n = N' W N, m x m
  Eigen::VectorXd normal_force;       // F_c of the samples that produced it (the Smith reference)
  Eigen::VectorXd normal_stiffness;   // (W_n^-1)_cc: what contact c feels with the others held still
  LocalModelGains gains;              // the gains for this stiffness
  GainSelection selection;            // how they were chosen (scheduling on)
  LocalModelKind local_model = LocalModelKind::pi;  // the mode the gains are for: the tick takes
  HoldKind hold = HoldKind::zoh;                    // it up with them when it differs
};

struct ContactOutput {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // sent to the device, after the safety layer
  Eigen::Vector3d proxy = Eigen::Vector3d::Zero();  // the device point moved onto the surface
  double normal_force = 0;                          // F_c from the local model
  double penetration = 0;                           // e_c behind the held surface
  bool in_contact = false;
  double port_energy_j = 0;      // E: energy from the hand into the rendering so far (passivity.h)
  double passivity_scale = 1;    // s: the share of the local model's force the layer let through
  // c: the change the layer's controller made to what the device can be sent (PassivityPort::
  // controller_force(); zero when it did nothing, with the layer off or observing).
  Eigen::Vector3d controller_force = Eigen::Vector3d::Zero();
  // On-line identification (identification.h): K and B of the force sent against the device's
  // depth, valid once the contact has moved enough; and the newest frame's (W_n^-1)_cc.
  double identified_stiffness_n_per_m = 0, identified_damping_n_s_per_m = 0;
  bool identified = false;
  double condensed_stiffness_n_per_m = 0;
};

// The frame-rate energy audit of one contact. The rendering between the hand and the tissue (the
// local model, the holds, the frame delay) is a two-port: energy enters it from the hand at the
// tick rate and leaves it into the tissue at the frame rate. Over the ticks of one frame, with f(k)
// the force sent at tick k (held until the next), x the device point, n the held normal, F_j the
// normal force of frame j's samples and p_j the surface point of the answer to them:
//     hand      = sum over the frame's ticks of -f(k-1) . (x(k) - x(k-1))      (the port observer's E)
//     tissue    = -(F_j-1 + F_j) / 2 n . (p_j - p_j-1), booked in the frame that takes p_j up
//                 (the trapezoid: exactly the change of a linear tissue's elastic energy)
//     held      = the sum of hand - tissue since the contact began: what the rendering holds or
//                 has dissipated. A rendering that starts empty is passive iff held >= 0 at all
//                 times (no storage function needed, as for the port observer); held < 0 is
//                 energy the loop generated and handed to the hand or the tissue.
//     generated = how much further below zero held went in this frame (0 if it did not)
// A frame that generated more than HapticLoopSettings::audit_tolerance_j is counted. Out of contact
// the rendering holds nothing, so held restarts at every contact (what one contact dissipated does
// not hide what the next generates). The P local model is a spring between the hand and the
// tissue and stays passive with a hand that does not ring it; PI and the Smith predictor drive the
// tissue's force towards the frame's equilibrium whatever the hand has put in, and a press through
// them typically hands the tissue more than the hand gave (docs/stability.md, section 11).
struct FrameEnergy {
  double hand_j = 0, tissue_j = 0, held_j = 0, generated_j = 0;
};

// The loop between two frames, in normal coordinates: what the lifting (stability_analysis.h)
// perturbs and reads back. Depths are along each contact's held normal, -n . point (into the
// tissue); forces are the samples' normal forces (the Smith predictor's reference). During frame j
// (before its first tick's promotion) the published answer is x_o(j-1), the newest held one x_o(j-2).
struct FrameBoundary {
  Eigen::VectorXd answer_depth, newest_depth;  // x_o(j-1), x_o(j-2)
  Eigen::VectorXd answer_force, newest_force;  // F((j-1)N), F((j-2)N): the forces that produced them
  Eigen::VectorXd integrator;                  // s(jN)
};

// How the identified stiffness of one contact compared with the condensed one, frame by frame.
struct IdentificationCheck {
  long frames_compared = 0;     // frame starts in contact with a valid identification
  long disagreements = 0;       // of those, relative difference over the bound
  long first_disagreement_frame = -1;
  double max_relative_difference = 0;
  double last_relative_difference = 0;
};

class HapticLoop {
 public:
  // `initial`: the environment's answer at rest (Environment::initial), held during frame 0.
  HapticLoop(const HapticLoopSettings& settings, const EnvironmentUpdate& initial);

  // One tick with the device points and their velocities (m of each). Real-time safe.
  const std::vector<ContactOutput>& tick(const std::vector<Eigen::Vector3d>& devices,
                                         const std::vector<Eigen::Vector3d>& velocities) noexcept;
  // The same with the velocities by backward differences of the points (zero at the first tick).
  const std::vector<ContactOutput>& tick(const std::vector<Eigen::Vector3d>& devices) noexcept;

  // True right after a tick that started a frame: samples() holds what to hand the environment.
  bool decimated() const { return decimated_; }
  const std::vector<ContactSample>& samples() const { return samples_; }
  long frame() const { return tick_count_ == 0 ? 0 : (tick_count_ - 1) / settings_.ratio; }

  // Producer side: the slot to fill (update.frames, compliance, ...) with the answer to samples(),
  // then prepare() and publish(). Allocates (gain selection); never call from the tick.
  // The hand-over is lock-free: four slots, two held by the tick (newest, previous: FOH needs
  // both), one being filled by the producer, one in the middle; publish() and the promotion at a
  // frame's first tick each swap a slot index with the middle atomically, so the producer may run
  // in another thread. Publishing twice before a promotion replaces the first update.
  FrameSlot& pending_slot() { return slots_[back_]; }
  // Fills the slot's compliance and gains for its mode (slot.local_model, slot.hold).
  void prepare(FrameSlot& slot) const;
  // All of the producer's part but publish(): the environment's answer to `samples` (those of
  // `frame`) into pending_slot(), the force that produced it (the Smith reference), prepare().
  FrameSlot& fill_answer(Environment& environment, const std::vector<ContactSample>& samples, long frame);
  void publish() noexcept {
    published_gains_ = slots_[back_].gains;
    bool replaced_unread = false;
    back_ = middle_.publish(back_, replaced_unread);
  }

  // Stopping (a request, a device's fault): every contact's force fades to zero over `ticks`
  // ticks from the next tick on, in the safety layer (force_safety.h), so what the hand is sent
  // and what the tissue is pressed with fade together. Real-time safe; asking again changes nothing.
  void ramp_out(long ticks) noexcept {
    for (ForceSafety& safety : safety_) safety.ramp_out(ticks);
  }
  bool ramped_out() const noexcept { return safety_.front().ramped_out(); }

  int contacts() const { return contacts_; }
  long ticks() const { return tick_count_; }
  const HapticLoopSettings& settings() const { return settings_; }
  const LocalModelGains& gains() const { return local_model_.gains(); }
  // The mode the tick renders with (the tick's thread, or after it, as in lockstep).
  LocalModelKind local_model() const { return local_model_.kind(); }
  HoldKind hold() const { return hold_; }
  const FrameSlot& newest() const { return slots_[newest_]; }
  const ForceSafety& safety(int contact) const { return safety_[contact]; }
  const PassivityPort& passivity(int contact) const { return passivity_[contact]; }
  const ContactIdentifier& identifier(int contact) const { return identifiers_[contact]; }
  const IdentificationCheck& identification(int contact) const { return checks_[contact]; }
  // The energy audit of the frame that ended at the last tick that started a frame (valid with
  // samples(): right after a tick that decimated), one per contact; and per contact the frames that
  // generated more than the tolerance, and the most one generated.
  const std::vector<FrameEnergy>& frame_energy() const { return frame_energy_; }
  long generating_frames(int contact) const { return generating_frames_[contact]; }
  double max_generated_j(int contact) const { return max_generated_[contact]; }
  // The frame boundary, between a publish() and the next tick (lockstep: after a tick that
  // decimated was answered). set_frame_boundary moves the two slots' points along their normals
  // and replaces the integrator; it throws if no answer is published. Neither is for the tick.
  void frame_boundary(FrameBoundary& out) const;
  void set_frame_boundary(const FrameBoundary& state);
  // Frame starts at which no new answer was there (real time: the solve outlasted its frame), and
  // the tick of the first (-1: none). Never in lockstep.
  long late_answers() const { return late_answers_; }
  long first_late_tick() const { return first_late_tick_; }

 private:
  void promote() noexcept;
  // The energy audit's share of a tick: the hand's work over the last tick; at a frame's end,
  // the frame's balance (FrameEnergy).
  void audit_tick(const std::vector<Eigen::Vector3d>& devices, bool frame_ends) noexcept;
  // A mode asked through settings_.modes, analysed on the pending slot's stiffness and answered.
  void consider_mode_switch(FrameSlot& slot);

  HapticLoopSettings settings_;
  int contacts_;
  LocalModel local_model_;
  std::array<FrameSlot, 4> slots_;
  int newest_ = 0, previous_ = 1;          // the tick's
  int back_ = 2;                           // the producer's
  SlotExchange middle_{3};                 // exchanged
  LocalModelGains published_gains_;        // the producer's warm start
  LocalModelKind producer_model_;          // the producer's mode: that of every slot it fills
  HoldKind producer_hold_;
  HoldKind hold_;                          // the tick's
  long tick_count_ = 0, newest_arrival_ = 0;
  long late_answers_ = 0, first_late_tick_ = -1;
  bool decimated_ = false;

  // Gain blend: from -> to over blend_ticks.
  LocalModelGains blend_from_, blend_to_;
  int blend_left_ = 0;

  std::vector<ContactFrame> held_;
  Eigen::VectorXd penetration_, zeros_, reference_;
  Eigen::VectorXd converged_force_;  // the samples' normal forces behind the last converged answer (producer side)
  std::vector<ContactSample> samples_;
  std::vector<ContactOutput> outputs_;
  std::vector<ForceSafety> safety_;
  std::vector<PassivityPort> passivity_;
  std::vector<ContactIdentifier> identifiers_;
  std::vector<IdentificationCheck> checks_;
  // The energy audit: the open frame's sums, the last tick's force, point and coupling stiffness.
  std::vector<FrameEnergy> frame_energy_, audit_open_;
  std::vector<Eigen::Vector3d> audit_force_, audit_point_;
  std::vector<char> audit_in_contact_;
  std::vector<double> audit_held_;
  std::vector<long> generating_frames_;
  std::vector<double> max_generated_;
  std::vector<Eigen::Vector3d> last_points_, velocities_;  // for tick(points) alone
};

// The lockstep session (replay, tests, studies): after every tick that started a frame, the
// environment solves at once and its answer is published for the next frame. Bit-for-bit
// reproducible. The environment's solve runs in the caller's thread, so this is not the real-time
// path (issue 6 wires that with a lock-free hand-over).
class LockstepSession {
 public:
  LockstepSession(HapticLoop& loop, Environment& environment) : loop_(loop), environment_(environment) {}
  const std::vector<ContactOutput>& tick(const std::vector<Eigen::Vector3d>& devices);
  const std::vector<ContactOutput>& tick(const std::vector<Eigen::Vector3d>& devices,
                                         const std::vector<Eigen::Vector3d>& velocities);
  // The producer side alone, after a tick that decimated: solve, prepare, publish.
  void answer();

 private:
  HapticLoop& loop_;
  Environment& environment_;
};

// Everything a session needs from the environment's rest state.
EnvironmentUpdate initial_update(Environment& environment);

}  // namespace fetouch::haptics
