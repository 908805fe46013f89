// The passivity layer: per contact, between the local model and the safety layer, at the tick rate.
// The lifting proof (stability_analysis.h) covers the loop with the device's motion as an input;
// a hand closes the loop through that motion, and a stiff rendering against a light, stiff grip can
// then ring although the proof holds. The layer watches the energy at the port the device sees and
// keeps the rendering from handing the hand energy it never put in.
//
// Observer (both controllers). The force f(k-1) is held over the tick that follows it (zero-order
// hold at the device), so the work it does is paired with the displacement that follows it:
//     E(k) = E(k-1) - f(k-1) . (x(k) - x(k-1))
// E is the energy that has flowed from the hand into the virtual environment (the tissue, the local
// model's springs, whatever the solver's frames do). A passive rendering keeps E >= 0 at all times;
// E < 0 is energy the sampled loop generated. Pairing f(k) with x(k) - x(k-1) instead (the
// displacement before it) would book the hold's own leak (K T |v|^2 / 2 per tick for a wall K) as
// dissipation, and the observer would never see a sampled wall ring.
//
// Controllers (mode on):
//   - scaling (the default): the layer scales the force it is handed, f = s f_req, 0 < s <= 1: the
//     stiffness the hand meets is s times the local model's. Colgate's bound says why this is the
//     lever: a sampled stiffness K against a hand of damping b is passive only for K < 2 b / T, and
//     a light, stiff, barely damped grip (or a hand that lets go) moves that bound far below what a
//     stiff tissue asks for; no damper added on top of the wall helps (a virtual damper only
//     tightens the bound), and a bounded additive force cannot keep pace with K v. The observer
//     drives s: a bank, set to A (the allowance) when a contact begins, gains the port's energy
//     each tick; when it falls below zero the contact has handed the hand A more than it was
//     given, the ceiling of s halves and the bank gets another A (a halving waits until s has
//     reached the last one; a contact that begins within bounce_gap_s of the last one's end is a
//     bounce of it and keeps its bank). Held energy only raises the bank: a compressed tissue springing back
//     is not generation. s follows the ceiling down at most max_step_n / |f_req| a tick (no force
//     step over max_step_n from the controller); the ceiling climbs back towards 1 at
//     recovery_per_s only between contacts, since raising the stiffness of a compressed spring
//     itself hands its owner energy. A contact whose bank never runs dry (a hand whose damping
//     absorbs the hold's leak, the nominal case) is never scaled. No division by a velocity: s
//     acts on the port's energy alone.
//     The bank alone cannot see a loop that rings about a deep press: the press put far more into
//     the springs (tens of mJ) than a ring generates a cycle (tenths of a mJ), and the ring can hand
//     that back cycle after cycle, held at the clamp, before the bank runs dry (plain PO/PC's "early
//     storage hides later generation"). So the layer also books each cycle: the depth d along the
//     force from where the contact began, its mean over cycle_mean_s, and E each time d crosses
//     that mean inwards (after having been cycle_band_m below it). Over a closed cycle a passive
//     port takes energy in (the area of its force-depth loop, whatever it stores), so a cycle in
//     which E fell is generation; between crossings at different depths the store's change, the
//     mean force times the change of depth, is taken off first (a press drifting in or out with a
//     tremor on it is not generation). Those falls add up (a dissipating cycle pays them back,
//     down to nothing owed), and when they pass the allowance the ceiling halves as for a dry bank.
//   - hannaford_ryu (the baseline of Hannaford & Ryu 2002): when E < 0, a damper
//     alpha = -E / (T |v|^2) dissipates the whole deficit over the next tick, c = alpha v
//     (f = f_req - alpha v); below a velocity floor it does nothing (alpha would be unbounded).
//     Its force is limited only by the safety layer's clamp, as published.
// Mode observe runs the observer alone (the force passes untouched); off skips even that.
//
// Real-time safe: no allocation, no locks, no exceptions.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>

namespace fetouch::haptics {

enum class PassivityMode { off, observe, on };
enum class PassivityControllerKind { scaling, hannaford_ryu };

// The names scenes and command lines use: "off", "observe", "on"; "scaling", "hannaford_ryu".
const char* to_string(PassivityMode mode);
const char* to_string(PassivityControllerKind kind);
bool parse_passivity_mode(const std::string& name, PassivityMode& mode);
bool parse_passivity_controller(const std::string& name, PassivityControllerKind& kind);

struct PassivitySettings {
  PassivityMode mode = PassivityMode::on;
  PassivityControllerKind controller = PassivityControllerKind::scaling;
  double period_s = 1e-3;          // T
  double allowance_j = 2e-5;       // A: energy a contact may lend the hand before the controller acts
  double max_step_n = 0.1;         // the controller's force changes by at most this per tick
  double recovery_per_s = 0.5;     // scaling: how fast the ceiling of s climbs back towards 1
  // scaling: a contact that begins within this long of the last one's end is a bounce of it (its
  // bank and ceiling carry on, and the ceiling does not climb in the gap).
  double bounce_gap_s = 0.25;
  // scaling: the cycle books (above): the depth's running mean's time constant, and how far the
  // depth must go below it and back above it for a crossing to count (noise is not a cycle).
  double cycle_mean_s = 0.05;
  double cycle_band_m = 2e-5;
  double velocity_floor_m_per_s = 1e-4;  // hannaford_ryu: no damping below this speed
  // The device's largest force (the safety layer's clamp): the controller's force is measured
  // against what the device could have been sent, not against a request beyond its reach.
  double max_force_n = 1e300;
};

// Throws std::invalid_argument naming the first value out of range (a period, allowance or bound
// that is not positive, or not finite).
void check(const PassivitySettings& settings);

class PassivityPort {
 public:
  explicit PassivityPort(const PassivitySettings& settings);

  // One tick: the device's position and velocity at its start and the force the local model asks
  // for; returns the force to hand the safety layer.
  Eigen::Vector3d filter(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                         const Eigen::Vector3d& requested) noexcept;
  // The force the device was actually sent this tick (after the safety layer): the observer pairs
  // it with the next tick's displacement.
  void sent(const Eigen::Vector3d& force) noexcept { last_force_ = force.allFinite() ? force : Eigen::Vector3d::Zero(); }

  const PassivitySettings& settings() const { return settings_; }
  double energy_j() const { return energy_; }                          // E
  // c of the last tick: the change the controller made to the force the device can be sent (both
  // the request and the controller's answer clamped to max_force_n).
  const Eigen::Vector3d& controller_force() const { return control_; }
  // Ticks at which the controller changed the force, ticks that ended with E < 0 ("generation"),
  // the number of times E went from >= 0 to < 0 (generation events), and the largest |c|.
  std::uint64_t controller_ticks() const { return controller_ticks_; }
  // Ticks at which the controller itself acted: scaling, those in contact at which s moved (a
  // halving and its descent; its recovery between contacts is not felt); hannaford_ryu, those at which its damper pushed. Under a steady s < 1
  // the force differs from the request (controller_ticks) while the controller does nothing new.
  std::uint64_t adjusting_ticks() const { return adjusting_ticks_; }
  std::uint64_t generating_ticks() const { return generating_ticks_; }
  std::uint64_t generation_events() const { return generation_events_; }
  double max_controller_force_n() const { return max_control_; }
  // The lowest E seen (J): how much energy the loop generated at worst.
  double min_energy_j() const { return min_energy_; }
  double scale() const { return scale_; }  // s (scaling)
  double min_scale() const { return min_scale_; }  // the lowest s so far

 private:
  Eigen::Vector3d scaling(const Eigen::Vector3d& position, const Eigen::Vector3d& requested) noexcept;
  // The cycle books of one tick in contact; true when the cycles have generated the allowance.
  bool cycle_generated(const Eigen::Vector3d& position, const Eigen::Vector3d& requested, bool new_contact) noexcept;
  Eigen::Vector3d hannaford_ryu(const Eigen::Vector3d& velocity) const noexcept;

  PassivitySettings settings_;
  bool started_ = false;
  Eigen::Vector3d last_position_ = Eigen::Vector3d::Zero(), last_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d control_ = Eigen::Vector3d::Zero();
  double energy_ = 0, min_energy_ = 0, max_control_ = 0;
  double bank_ = 0, scale_ = 1, ceiling_ = 1, min_scale_ = 1;
  bool touching_ = false;
  // The cycle books: where the contact began, the depth's running mean, whether the depth has been
  // below it, E at the last inward crossing (has_cycle_: one seen), and the generation owed.
  Eigen::Vector3d contact_point_ = Eigen::Vector3d::Zero();
  double depth_mean_ = 0, cycle_energy_ = 0, cycle_depth_ = 0, cycle_force_ = 0, cycle_debt_ = 0;
  bool below_mean_ = false, has_cycle_ = false;
  long bounce_ticks_;             // bounce_gap_s in ticks
  double mean_weight_;            // the depth's running mean: T / cycle_mean_s, at most 1
  long apart_ticks_ = 1L << 40;  // ticks since the last contact ended
  std::uint64_t controller_ticks_ = 0, adjusting_ticks_ = 0, generating_ticks_ = 0, generation_events_ = 0;
};

}  // namespace fetouch::haptics
