#include "haptics/haptic_loop.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace fetouch::haptics {

namespace {
// A force passed on at less than this share of the request was cut (scaled or clamped).
constexpr double kUncutShare = 0.999;
}  // namespace

HapticLoop::HapticLoop(const HapticLoopSettings& settings, const EnvironmentUpdate& initial)
    : settings_(settings),
      contacts_(static_cast<int>(initial.frames.size())),
      local_model_(settings.local_model, contacts_),
      producer_model_(settings.local_model),
      producer_hold_(settings.hold),
      hold_(settings.hold) {
  if (contacts_ < 1) throw std::invalid_argument("HapticLoop: at least one contact");
  if (settings.ratio < 1) throw std::invalid_argument("HapticLoop: the ratio N must be at least 1");
  if (initial.compliance.rows() != 3 * contacts_ || initial.compliance.cols() != 3 * contacts_)
    throw std::invalid_argument("HapticLoop: the compliance must be 3m x 3m");
  local_model_.set_unilateral(settings.unilateral);
  local_model_.set_integrator_limit(settings.integrator_limit_n);
  for (FrameSlot& slot : slots_) {
    slot.update = initial;
    slot.normal_force = Eigen::VectorXd::Zero(contacts_);
    slot.local_model = settings.local_model;
    slot.hold = settings.hold;
  }
  converged_force_ = Eigen::VectorXd::Zero(contacts_);  // the rest state's: no force
  FrameSlot& first = slots_[newest_];
  first.gains = settings.gains;
  prepare(first);
  slots_[previous_] = first;
  slots_[2] = slots_[3] = first;  // sized like the others, so filling them never allocates more than once
  published_gains_ = first.gains;
  local_model_.set_gains(first.gains);
  local_model_.set_compliance(first.normal_compliance);
  held_.resize(contacts_);
  penetration_ = Eigen::VectorXd::Zero(contacts_);
  zeros_ = Eigen::VectorXd::Zero(contacts_);
  reference_ = Eigen::VectorXd::Zero(contacts_);
  samples_.resize(contacts_);
  outputs_.resize(contacts_);
  safety_.assign(contacts_, ForceSafety(settings.safety));
  PassivitySettings passivity = settings.passivity;
  passivity.period_s = settings.period_s;
  passivity.max_force_n = settings.safety.max_force_n;
  passivity_.assign(contacts_, PassivityPort(passivity));
  identifiers_.assign(contacts_, ContactIdentifier(settings.identification));
  checks_.assign(contacts_, IdentificationCheck{});
  frame_energy_.assign(contacts_, FrameEnergy{});
  audit_open_.assign(contacts_, FrameEnergy{});
  audit_force_.assign(contacts_, Eigen::Vector3d::Zero());
  audit_point_.assign(contacts_, Eigen::Vector3d::Zero());
  audit_in_contact_.assign(contacts_, 0);
  audit_held_.assign(contacts_, 0.0);
  generating_frames_.assign(contacts_, 0);
  max_generated_.assign(contacts_, 0.0);
  last_points_.assign(contacts_, Eigen::Vector3d::Zero());
  velocities_.assign(contacts_, Eigen::Vector3d::Zero());
}

void HapticLoop::prepare(FrameSlot& slot) const {
  const int m = contacts_;
  Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(3 * m, m);
  for (int c = 0; c < m; ++c) normals.block<3, 1>(3 * c, c) = slot.update.frames[c].normal;
  slot.normal_compliance = normals.transpose() * slot.update.compliance * normals;
  if (!settings_.coupling) slot.normal_compliance = Eigen::MatrixXd(slot.normal_compliance.diagonal().asDiagonal());
  GainProblem problem;
  problem.local_model = slot.local_model;
  problem.hold = slot.hold;
  problem.ratio = settings_.ratio;
  problem.stiffness = Eigen::LDLT<Eigen::MatrixXd>(slot.normal_compliance).solve(Eigen::MatrixXd::Identity(m, m));
  slot.normal_stiffness = problem.stiffness.diagonal();
  if (slot.update.damping.size()) {
    problem.damping = normals.transpose() * slot.update.damping * normals;
    if (!settings_.coupling) problem.damping = Eigen::MatrixXd(problem.damping.diagonal().asDiagonal());
  }
  if (!settings_.schedule_gains) {  // the given gains, and how stable they are for this stiffness
    slot.gains = settings_.gains;
    slot.selection.gains = settings_.gains;
    slot.selection.spectral_radius = robust_spectral_radius(problem, settings_.gains, settings_.selection);
    slot.selection.stable = slot.selection.spectral_radius < 1;
    return;
  }
  const LocalModelGains start = published_gains_;  // the producer's own: newest_ belongs to the tick
  slot.selection = select_gains(problem, settings_.selection, &start);
  // A selection that finds nothing robustly stable keeps the least unstable gains it saw; the
  // recording shows it (selection.stable) and the safety layer still bounds the force.
  slot.gains = slot.selection.gains;
}

namespace {

double depth(const ContactFrame& frame) { return -frame.normal.dot(frame.point); }

void set_depth(ContactFrame& frame, double to) { frame.point -= (to - depth(frame)) * frame.normal; }

}  // namespace

void HapticLoop::frame_boundary(FrameBoundary& out) const {
  const FrameSlot& answer = slots_[middle_.peek()];
  const FrameSlot& newest = slots_[newest_];
  out.answer_depth.resize(contacts_), out.newest_depth.resize(contacts_);
  for (int c = 0; c < contacts_; ++c) {
    out.answer_depth(c) = depth(answer.update.frames[c]);
    out.newest_depth(c) = depth(newest.update.frames[c]);
  }
  out.answer_force = answer.normal_force;
  out.newest_force = newest.normal_force;
  out.integrator = local_model_.integrator();
}

void HapticLoop::set_frame_boundary(const FrameBoundary& state) {
  if (!middle_.fresh()) throw std::logic_error("HapticLoop::set_frame_boundary: no answer is published");
  FrameSlot& answer = slots_[middle_.peek()];
  FrameSlot& newest = slots_[newest_];
  for (int c = 0; c < contacts_; ++c) {
    set_depth(answer.update.frames[c], state.answer_depth(c));
    set_depth(newest.update.frames[c], state.newest_depth(c));
  }
  answer.normal_force = state.answer_force;
  newest.normal_force = state.newest_force;
  local_model_.set_integrator(state.integrator);
}

void HapticLoop::promote() noexcept {
  // The old previous goes to the middle, the published update comes out of it.
  const int published = middle_.take(previous_);
  previous_ = newest_;
  newest_ = published;
  newest_arrival_ = tick_count_;
  const FrameSlot& slot = slots_[newest_];
  // The tissue's surface moves to the answer now: the work the samples' forces did on it.
  const FrameSlot& before = slots_[previous_];
  for (int c = 0; c < contacts_; ++c) {
    const Eigen::Vector3d& normal = slot.update.frames[c].normal;
    const double moved = normal.dot(slot.update.frames[c].point - before.update.frames[c].point);
    audit_open_[c].tissue_j += -0.5 * (slot.normal_force(c) + before.normal_force(c)) * moved;
  }
  local_model_.set_compliance(slot.normal_compliance);
  hold_ = slot.hold;
  if (slot.local_model != local_model_.kind()) {  // a switch the producer accepted: its gains at once
    local_model_.set_kind(slot.local_model);
    local_model_.set_gains(slot.gains);
    blend_left_ = 0;
    return;
  }
  if (slot.gains.proportional != local_model_.gains().proportional ||
      slot.gains.integral != local_model_.gains().integral) {
    blend_from_ = local_model_.gains();
    blend_to_ = slot.gains;
    blend_left_ = std::max(1, settings_.blend_ticks);
  }
}

const std::vector<ContactOutput>& HapticLoop::tick(const std::vector<Eigen::Vector3d>& devices) noexcept {
  for (int c = 0; c < contacts_; ++c) {
    velocities_[c] = tick_count_ == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d((devices[c] - last_points_[c]) / settings_.period_s);
    last_points_[c] = devices[c];
  }
  return tick(devices, velocities_);
}

const std::vector<ContactOutput>& HapticLoop::tick(const std::vector<Eigen::Vector3d>& devices,
                                                   const std::vector<Eigen::Vector3d>& velocities) noexcept {
  const int n = settings_.ratio;
  const int i = static_cast<int>(tick_count_ % n);
  audit_tick(devices, i == 0 && tick_count_ > 0);
  if (i == 0 && tick_count_ > 0) {
    if (middle_.fresh()) {
      promote();
    } else {
      if (late_answers_ == 0) first_late_tick_ = tick_count_;
      ++late_answers_;
    }
  }

  if (blend_left_ > 0) {
    --blend_left_;
    const double t = 1.0 - static_cast<double>(blend_left_) / std::max(1, settings_.blend_ticks);
    local_model_.set_gains({blend_from_.proportional + t * (blend_to_.proportional - blend_from_.proportional),
                            blend_from_.integral + t * (blend_to_.integral - blend_from_.integral)});
  }

  // Ticks since the newest answer was taken up: i itself while answers arrive on time (always in
  // lockstep). A late answer (real time, a solve that outlasted its frame) leaves the FOH at the
  // newest surface rather than starting over from the previous one, and pauses the integrator,
  // whose frame of integration the stability analysis covers is then complete.
  const long age = tick_count_ - newest_arrival_;
  const int held_tick = static_cast<int>(std::min<long>(age, n));
  local_model_.set_integrating(age < n);
  const FrameSlot& newest = slots_[newest_];
  const FrameSlot& previous = slots_[previous_];
  const double t = hold_weight(hold_, held_tick, n);
  for (int c = 0; c < contacts_; ++c) {
    if (hold_ == HoldKind::zoh)
      held_[c] = newest.update.frames[c];
    else
      interpolate(previous.update.frames[c], newest.update.frames[c], t, held_[c]);
    penetration_(c) = locate(held_[c], devices[c]).penetration;
  }
  apply_hold(hold_, held_tick, n, newest.normal_force, previous.normal_force, reference_);
  const Eigen::VectorXd& force = local_model_.step(penetration_, zeros_, reference_);
  const Eigen::VectorXd& predicted = local_model_.predicted_penetration();

  const double age_s = static_cast<double>(age) * settings_.period_s;
  decimated_ = i == 0;
  for (int c = 0; c < contacts_; ++c) {
    ContactOutput& out = outputs_[c];
    const Eigen::Vector3d& normal = held_[c].normal;
    out.normal_force = force(c);
    out.penetration = penetration_(c);
    out.in_contact = force(c) > 0;
    PassivityPort& port = passivity_[c];
    const Eigen::Vector3d requested = force(c) * normal;
    out.force = safety_[c].filter(port.filter(devices[c], velocities[c], requested), age_s);
    port.sent(out.force);
    // An integrator whose force was cut (scaled or clamped) holds until it passes again: behind the
    // cut it would only wind up.
    local_model_.set_integrating(c, !(out.force.norm() < kUncutShare * requested.norm()));
    out.port_energy_j = port.energy_j();
    out.passivity_scale = port.scale();
    out.controller_force = port.controller_force();
    audit_force_[c] = out.force;
    audit_in_contact_[c] = out.in_contact;
    ContactIdentifier& identifier = identifiers_[c];
    identifier.update(devices[c], velocities[c], normal, out.force, out.in_contact);
    out.identified = identifier.valid() && out.in_contact;
    out.identified_stiffness_n_per_m = identifier.stiffness_n_per_m();
    out.identified_damping_n_s_per_m = identifier.damping_n_s_per_m();
    out.condensed_stiffness_n_per_m = newest.normal_stiffness(c);
    if (decimated_ && out.identified && out.condensed_stiffness_n_per_m > 0) {
      IdentificationCheck& check = checks_[c];
      const double difference =
          std::abs(out.identified_stiffness_n_per_m - out.condensed_stiffness_n_per_m) / out.condensed_stiffness_n_per_m;
      ++check.frames_compared;
      check.last_relative_difference = difference;
      check.max_relative_difference = std::max(check.max_relative_difference, difference);
      if (difference > settings_.identification_bound) {
        if (check.disagreements == 0) check.first_disagreement_frame = tick_count_ / n;
        ++check.disagreements;
      }
    }
    // In contact the proxy sits on the (predicted) surface: the device moved out by the predicted
    // penetration along the normal; out of contact it is the device point.
    out.proxy = out.in_contact ? Eigen::Vector3d(devices[c] + predicted(c) * normal) : devices[c];
    if (decimated_) {
      // The tissue is pressed with the force the hand is sent (action and reaction at the device),
      // not the one the local model asked for.
      const double sent_normal = out.force.dot(normal);
      ContactSample& sample = samples_[c];
      sample.position = devices[c];
      sample.force = -sent_normal * normal;
      sample.normal_force = sent_normal;
      sample.in_contact = out.in_contact;
    }
  }
  ++tick_count_;
  return outputs_;
}

void HapticLoop::audit_tick(const std::vector<Eigen::Vector3d>& devices, bool frame_ends) noexcept {
  for (int c = 0; c < contacts_; ++c) {
    FrameEnergy& open = audit_open_[c];
    const double work = -audit_force_[c].dot(devices[c] - audit_point_[c]);
    if (std::isfinite(work)) open.hand_j += work;  // a device's glitch is the safety layer's, not the books'
    audit_point_[c] = devices[c];
    if (!frame_ends) continue;
    const double held_before = audit_held_[c];
    open.held_j = audit_held_[c] = held_before + open.hand_j - open.tissue_j;
    open.generated_j = std::max(0.0, std::max(0.0, -open.held_j) - std::max(0.0, -held_before));
    if (open.generated_j > settings_.audit_tolerance_j) ++generating_frames_[c];
    max_generated_[c] = std::max(max_generated_[c], open.generated_j);
    frame_energy_[c] = open;
    // Out of contact the coupling holds nothing: the next contact's books start afresh (what this
    // one dissipated does not hide what a later one generates).
    if (!audit_in_contact_[c]) audit_held_[c] = 0;
    open = FrameEnergy{};
  }
}

const std::vector<ContactOutput>& LockstepSession::tick(const std::vector<Eigen::Vector3d>& devices) {
  const std::vector<ContactOutput>& out = loop_.tick(devices);
  if (loop_.decimated()) answer();
  return out;
}

const std::vector<ContactOutput>& LockstepSession::tick(const std::vector<Eigen::Vector3d>& devices,
                                                        const std::vector<Eigen::Vector3d>& velocities) {
  const std::vector<ContactOutput>& out = loop_.tick(devices, velocities);
  if (loop_.decimated()) answer();
  return out;
}

FrameSlot& HapticLoop::fill_answer(Environment& environment, const std::vector<ContactSample>& samples, long frame) {
  FrameSlot& slot = pending_slot();
  environment.solve(samples, frame, slot.update);
  // The Smith reference is the force that produced the surface the answer holds. A frame that
  // failed hands back the last converged answer (environment.h), made under that frame's forces,
  // not this one's: taken as this one's, the predictor would see no give for the force added since,
  // and the integrator would wind the force up frame after frame (a deep press whose frames failed
  // went to the 3.3 N clamp in 0.3 s, at an unchanged depth).
  if (slot.update.status.converged)
    for (int c = 0; c < contacts_; ++c) converged_force_(c) = samples[c].normal_force;
  slot.normal_force = converged_force_;
  slot.local_model = producer_model_;
  slot.hold = producer_hold_;
  prepare(slot);
  consider_mode_switch(slot);
  return slot;
}

void HapticLoop::consider_mode_switch(FrameSlot& slot) {
  ModeVerdict verdict;
  if (!settings_.modes || !settings_.modes->take(verdict.request, verdict.local_model, verdict.hold)) return;
  const auto mode = [](LocalModelKind model, HoldKind hold) { return std::string(to_string(model)) + " + " + to_string(hold); };
  const std::string asked = mode(verdict.local_model, verdict.hold), kept = mode(producer_model_, producer_hold_);
  char text[300];
  if (verdict.local_model == producer_model_ && verdict.hold == producer_hold_) {
    verdict.accepted = true;
    verdict.gains = slot.gains;
    verdict.spectral_radius = slot.selection.spectral_radius;
    std::snprintf(text, sizeof text, "%s already", asked.c_str());
    verdict.text = text;
    settings_.modes->answer(verdict);
    return;
  }
  // What prepare() changes for another mode (the compliance it recomputes is the same).
  const LocalModelGains kept_gains = slot.gains;
  const GainSelection kept_selection = slot.selection;
  slot.local_model = verdict.local_model;
  slot.hold = verdict.hold;
  prepare(slot);
  verdict.gains = slot.gains;
  verdict.spectral_radius = slot.selection.spectral_radius;
  verdict.accepted = slot.selection.stable;
  const double margin = 100 * settings_.selection.margin;
  if (verdict.accepted) {
    producer_model_ = verdict.local_model;
    producer_hold_ = verdict.hold;
    std::snprintf(text, sizeof text, "%s from frame %ld: Kh %.4g N/m, N I %.4g N/m, robust spectral radius %.3f (K known within %.0f %%)",
                  asked.c_str(), slot.update.frame + 1, slot.gains.proportional, settings_.ratio * slot.gains.integral,
                  slot.selection.spectral_radius, margin);
  } else {
    if (settings_.schedule_gains)
      std::snprintf(text, sizeof text,
                    "refused %s: no gains robustly stable at this stiffness (the best found, Kh %.4g N/m, has a spectral "
                    "radius of %.3f >= 1 with K known within %.0f %%); %s stays",
                    asked.c_str(), slot.gains.proportional, slot.selection.spectral_radius, margin, kept.c_str());
    else
      std::snprintf(text, sizeof text,
                    "refused %s: the scene's gains (Kh %.4g N/m, N I %.4g N/m) give it a spectral radius of %.3f >= 1 "
                    "with K known within %.0f %%; %s stays",
                    asked.c_str(), slot.gains.proportional, settings_.ratio * slot.gains.integral,
                    slot.selection.spectral_radius, margin, kept.c_str());
    slot.local_model = producer_model_, slot.hold = producer_hold_;
    slot.gains = kept_gains, slot.selection = kept_selection;
  }
  verdict.text = text;
  settings_.modes->answer(verdict);
}

void LockstepSession::answer() {
  loop_.fill_answer(environment_, loop_.samples(), loop_.frame());
  loop_.publish();
}

EnvironmentUpdate initial_update(Environment& environment) {
  EnvironmentUpdate update;
  environment.initial(update);
  return update;
}

}  // namespace fetouch::haptics
