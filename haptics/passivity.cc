#include "haptics/passivity.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptics/force_safety.h"

namespace fetouch::haptics {

namespace {

// Below this much generated energy (1 uJ) rounding, not the loop, is speaking.
constexpr double kGenerationThresholdJ = 1e-6;

}  // namespace

const char* to_string(PassivityMode mode) {
  switch (mode) {
    case PassivityMode::off: return "off";
    case PassivityMode::observe: return "observe";
    case PassivityMode::on: return "on";
  }
  return "?";
}

const char* to_string(PassivityControllerKind kind) {
  return kind == PassivityControllerKind::scaling ? "scaling" : "hannaford_ryu";
}

bool parse_passivity_mode(const std::string& name, PassivityMode& mode) {
  for (PassivityMode m : {PassivityMode::off, PassivityMode::observe, PassivityMode::on})
    if (name == to_string(m)) return mode = m, true;
  return false;
}

bool parse_passivity_controller(const std::string& name, PassivityControllerKind& kind) {
  for (PassivityControllerKind k : {PassivityControllerKind::scaling, PassivityControllerKind::hannaford_ryu})
    if (name == to_string(k)) return kind = k, true;
  return false;
}

void check(const PassivitySettings& s) {
  const auto positive = [](double value, const char* name) {
    if (!(value > 0) || !std::isfinite(value))
      throw std::invalid_argument(std::string("passivity: ") + name + " must be positive and finite, not " +
                                  std::to_string(value));
  };
  positive(s.period_s, "the period");
  positive(s.recovery_per_s, "recovery_per_s");
  if (!(s.bounce_gap_s >= 0) || !std::isfinite(s.bounce_gap_s))
    throw std::invalid_argument("passivity: bounce_gap_s must be zero or more and finite, not " + std::to_string(s.bounce_gap_s));
  positive(s.max_step_n, "max_step_n");
  positive(s.velocity_floor_m_per_s, "velocity_floor_m_per_s");
  positive(s.cycle_mean_s, "cycle_mean_s");
  positive(s.cycle_band_m, "cycle_band_m");
  positive(s.max_force_n, "the device's largest force");
  if (!(s.allowance_j >= 0) || !std::isfinite(s.allowance_j))
    throw std::invalid_argument("passivity: allowance_j must be zero or more and finite, not " + std::to_string(s.allowance_j));
}

PassivityPort::PassivityPort(const PassivitySettings& settings)
    : settings_(settings),
      bounce_ticks_((check(settings), std::lround(settings.bounce_gap_s / settings.period_s))),
      mean_weight_(std::min(1.0, settings.period_s / settings.cycle_mean_s)) {}

Eigen::Vector3d PassivityPort::filter(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                                      const Eigen::Vector3d& requested) noexcept {
  if (settings_.mode == PassivityMode::off) return requested;
  // The observer: last tick's force over the displacement that followed it.
  if (started_ && position.allFinite()) {
    const bool was_generating = energy_ < -kGenerationThresholdJ;
    const double work = -last_force_.dot(position - last_position_);
    energy_ += work;
    bank_ += work;
    const bool generating = energy_ < -kGenerationThresholdJ;
    generating_ticks_ += generating;
    generation_events_ += generating && !was_generating;
    min_energy_ = std::min(min_energy_, energy_);
  }
  if (position.allFinite()) last_position_ = position, started_ = true;
  if (settings_.mode == PassivityMode::observe || !requested.allFinite() || !velocity.allFinite()) {
    control_.setZero();
    return requested;
  }

  const Eigen::Vector3d before = control_;
  const double scale_before = scale_;
  Eigen::Vector3d force;
  if (settings_.controller == PassivityControllerKind::scaling) {
    force = scaling(position, requested);
    adjusting_ticks_ += scale_ != scale_before && requested.squaredNorm() > 0;  // out of contact s moves unfelt
  } else {
    const Eigen::Vector3d damping = hannaford_ryu(velocity);
    adjusting_ticks_ += damping.squaredNorm() > 0;
    force = requested - damping;
  }
  control_ = clamp_magnitude(requested, settings_.max_force_n) - clamp_magnitude(force, settings_.max_force_n);
  if (control_.squaredNorm() > 0 || before.squaredNorm() > 0) {
    controller_ticks_ += control_ != before;
    max_control_ = std::max(max_control_, control_.norm());
  }
  return force;
}

Eigen::Vector3d PassivityPort::scaling(const Eigen::Vector3d& position, const Eigen::Vector3d& requested) noexcept {
  const double request = requested.norm();
  const bool touching = request > 0;
  // A contact that begins within bounce_gap_s of the last one's end is a bounce of it (the hand
  // thrown off and back): its bank and ceiling carry on. Reset at every touch, each bounce would
  // start with a fresh allowance, and a hand could bounce three to five times before s fell.
  const bool new_contact = touching && !touching_ && apart_ticks_ > bounce_ticks_;
  if (new_contact) bank_ = settings_.allowance_j;
  apart_ticks_ = touching ? 0 : apart_ticks_ + 1;
  touching_ = touching;
  const bool cycles_generated = touching && position.allFinite() && cycle_generated(position, requested, new_contact);
  // The bank is A plus the port's energy since the contact began, plus A for each halving: it is
  // below zero only when the contact has handed the hand (halvings + 1) A more than it was given,
  // whatever the springs hold (held energy only raises it).
  if ((bank_ < 0 || cycles_generated) && touching) {
    // Halve the stiffness, unless s is still on its way down to the last halving (not yet acting).
    if (scale_ <= 1.05 * ceiling_) ceiling_ = 0.5 * scale_, cycle_debt_ = 0;
    if (bank_ < 0) bank_ += settings_.allowance_j;
  }
  // Out of contact the ceiling climbs back; in contact it holds: raising the stiffness of a
  // compressed spring hands its owner energy (K x^2 / 2 for each unit of K), which is what the layer
  // is there to prevent.
  if (!touching && apart_ticks_ > bounce_ticks_) ceiling_ = std::min(1.0, ceiling_ + settings_.recovery_per_s * settings_.period_s);
  // s follows the ceiling, its force step bounded by max_step_n (any step at all out of contact).
  const double step = touching ? settings_.max_step_n / request : 1.0;
  scale_ = std::clamp(ceiling_, scale_ - step, scale_ + step);
  min_scale_ = std::min(min_scale_, scale_);
  return scale_ * requested;
}

bool PassivityPort::cycle_generated(const Eigen::Vector3d& position, const Eigen::Vector3d& requested,
                                    bool new_contact) noexcept {
  if (new_contact) {
    contact_point_ = position;
    depth_mean_ = cycle_debt_ = 0;
    below_mean_ = has_cycle_ = false;
  }
  // The force pushes the hand out of the tissue: depth grows against it.
  const double depth = requested.normalized().dot(contact_point_ - position);
  depth_mean_ += (depth - depth_mean_) * mean_weight_;
  if (depth < depth_mean_ - settings_.cycle_band_m) below_mean_ = true;
  if (below_mean_ && depth > depth_mean_ + settings_.cycle_band_m) {
    below_mean_ = false;  // an inward crossing: one cycle closed since the last
    // Between two crossings the springs' store changed by about the mean force times the change
    // of depth (exact for a linear spring): a press that drifts in or out is not a cycle's work.
    const double force = last_force_.norm();
    if (has_cycle_) {
      const double stored = 0.5 * (force + cycle_force_) * (depth - cycle_depth_);
      cycle_debt_ = std::max(0.0, cycle_debt_ + stored - (energy_ - cycle_energy_));
    }
    cycle_energy_ = energy_, cycle_depth_ = depth, cycle_force_ = force, has_cycle_ = true;
  }
  return cycle_debt_ > settings_.allowance_j;  // paid off by the halving it asks for
}

Eigen::Vector3d PassivityPort::hannaford_ryu(const Eigen::Vector3d& velocity) const noexcept {
  const double speed2 = velocity.squaredNorm();
  if (!(energy_ < 0) || speed2 < settings_.velocity_floor_m_per_s * settings_.velocity_floor_m_per_s)
    return Eigen::Vector3d::Zero();
  const double alpha = -energy_ / (settings_.period_s * speed2);
  return alpha * velocity;  // f = f_req - alpha v: a damper against the motion
}

}  // namespace fetouch::haptics
