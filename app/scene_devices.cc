#include "app/scene_devices.h"

#include <stdexcept>
#include <string>

#include "haptics/phantom.h"

namespace fetouch::app {

haptics::HapticLoopSettings loop_settings(const config::Scene& scene) {
  const config::Haptics& h = scene.haptics;
  haptics::HapticLoopSettings s;
  haptics::parse_local_model(config::to_string(h.local_model), s.local_model);  // the same names
  s.hold = h.hold == config::HoldType::foh ? haptics::HoldKind::foh : haptics::HoldKind::zoh;
  s.ratio = h.ratio(scene.solver);
  s.period_s = 1 / h.rate_hz;
  s.schedule_gains = h.automatic_gains;
  s.coupling = h.coupling;
  s.gains = {h.proportional_n_per_m, h.integral_n_per_m};
  s.selection.margin = h.robustness_margin;
  s.selection.period_s = s.period_s;
  if (h.design_hand.enabled) {
    haptics::HandParameters hand;
    hand.mass_kg = h.design_hand.mass_kg;
    hand.stiffness_n_per_m = h.design_hand.stiffness_n_per_m;
    hand.damping_n_s_per_m = h.design_hand.damping_n_s_per_m;
    s.selection.hand = hand;
  }
  s.safety.max_force_n = h.max_force_n;
  s.safety.max_force_rate_n_per_s = h.max_force_rate_n_per_s;
  s.safety.period_s = s.period_s;
  s.safety.watchdog_timeout_s = h.watchdog_timeout_s;
  const config::Passivity& p = h.passivity;
  s.passivity.mode = p.mode == config::PassivityModeType::on        ? haptics::PassivityMode::on
                     : p.mode == config::PassivityModeType::observe ? haptics::PassivityMode::observe
                                                                    : haptics::PassivityMode::off;
  s.passivity.controller = p.controller == config::PassivityControllerType::scaling
                               ? haptics::PassivityControllerKind::scaling
                               : haptics::PassivityControllerKind::hannaford_ryu;
  s.passivity.allowance_j = p.allowance_j;
  s.passivity.max_step_n = p.max_step_n;
  s.passivity.recovery_per_s = p.recovery_per_s;
  s.passivity.period_s = s.period_s;
  s.identification.enabled = h.identification.enabled;
  s.identification.forgetting = h.identification.forgetting;
  s.identification_bound = h.identification.bound;
  return s;
}

haptics::HandParameters hand_parameters(const config::HandModel& hand) {
  haptics::HandParameters p;
  p.model = hand.model == config::HandKind::stylus ? haptics::HandModelKind::stylus : haptics::HandModelKind::one_mass;
  p.mass_kg = hand.mass_kg, p.stiffness_n_per_m = hand.stiffness_n_per_m, p.damping_n_s_per_m = hand.damping_n_s_per_m;
  p.handle_mass_kg = hand.handle_mass_kg;
  p.arm_stiffness_n_per_m = hand.arm_stiffness_n_per_m, p.arm_damping_n_s_per_m = hand.arm_damping_n_s_per_m;
  return p;
}

std::vector<haptics::HandEvent> hand_events(const config::HandModel& hand) {
  std::vector<haptics::HandEvent> out;
  for (const config::HandEvent& e : hand.events) {
    haptics::HandEvent h;
    h.kind = e.type == config::HandEventType::release ? haptics::HandEventKind::release
             : e.type == config::HandEventType::grip  ? haptics::HandEventKind::grip
             : e.type == config::HandEventType::tremor ? haptics::HandEventKind::tremor
                                                       : haptics::HandEventKind::impact;
    h.at_s = e.at_s, h.factor = e.factor, h.ramp_s = e.ramp_s;
    h.frequency_hz = e.frequency_hz, h.amplitude_m = e.amplitude_m, h.speed_m_per_s = e.speed_m_per_s;
    h.direction = Eigen::Vector3d(e.direction[0], e.direction[1], e.direction[2]);
    out.push_back(h);
  }
  return out;
}

haptics::WorkspaceMapping workspace_mapping(const config::Device& device) {
  haptics::WorkspaceMapping m;
  const config::Vec3* axes[3] = {&device.x_axis, &device.y_axis, &device.z_axis};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m.rotation(r, c) = (*axes[c])[r];
  m.scale = device.scale;
  m.offset_m = Eigen::Vector3d(device.offset_m[0], device.offset_m[1], device.offset_m[2]);
  m.engage_button = device.engage_button;
  m.clutch_button = device.clutch_button;
  return m;
}

std::unique_ptr<haptics::Device> make_device(const config::Probe& probe, const config::Scene& scene,
                                             const haptics::HapticLoopSettings& settings, const haptics::Trajectory* path) {
  const config::Device& d = probe.device;
  switch (d.type) {
    case config::DeviceType::replay:
    case config::DeviceType::operator_model:
      if (!path) throw std::runtime_error("probe " + probe.name + ": a " + config::to_string(d.type) + " device needs a trajectory");
      if (d.type == config::DeviceType::replay) return std::make_unique<haptics::ReplayDevice>(*path, settings.period_s);
      return std::make_unique<haptics::VirtualOperator>(
          *path, hand_parameters(d.hand), settings.period_s, hand_events(d.hand));
    case config::DeviceType::phantom: {
      haptics::PhantomSettings p;
      p.name = d.phantom_name;
      p.library = d.library;
      p.max_force_n = scene.haptics.max_force_n;
      p.period_s = settings.period_s;
      p.mapping = workspace_mapping(d);
      try {
        return std::make_unique<haptics::PhantomDevice>(p);
      } catch (const std::exception& e) {
        throw std::runtime_error("probe " + probe.name + ": " + e.what());
      }
    }
    default:
      throw std::runtime_error("probe " + probe.name + ": the " + std::string(config::to_string(d.type)) +
                               " device is driven in the trainer window: fetouch trainer SCENE");
  }
}

}  // namespace fetouch::app
