// The sections of a scene that configure the session: `solver`, `haptics`, `probes`, and the
// rules that tie sections together.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <string>

#include "config/plausible.h"
#include "config/section_readers.h"

namespace fetouch::config {
namespace detail {
namespace {

const Choices<LinearSolver> kLinearSolvers{{"auto", LinearSolver::automatic},
                                           {"direct", LinearSolver::direct},
                                           {"cg_amg", LinearSolver::cg_amg}};
const Choices<LocalModelType> kLocalModels{{"p", LocalModelType::p},
                                           {"pi", LocalModelType::pi},
                                           {"smith", LocalModelType::smith},
                                           {"pi_smith", LocalModelType::pi_smith}};
const Choices<HoldType> kHolds{{"zoh", HoldType::zoh}, {"foh", HoldType::foh}};
const Choices<PassivityModeType> kPassivityModes{
    {"off", PassivityModeType::off}, {"observe", PassivityModeType::observe}, {"on", PassivityModeType::on}};
const Choices<PassivityControllerType> kPassivityControllers{{"scaling", PassivityControllerType::scaling},
                                                             {"hannaford_ryu", PassivityControllerType::hannaford_ryu}};

void read_passivity(MapView& haptics, Passivity& out) {
  const Entry e = haptics.entry("passivity");
  MapView map(haptics.reader(), e.value, e.path, e.key_mark,
              {"mode", "controller", "allowance_j", "max_step_n", "recovery_per_s"});
  if (!map.valid()) return;
  map.choice("mode", out.mode, kPassivityModes);
  map.choice("controller", out.controller, kPassivityControllers);
  map.number("allowance_j", out.allowance_j, {0, 10, false, false, "0 to 10 J"});
  map.number("max_step_n", out.max_step_n, {0, 100, true, false, "over 0, up to 100 N"});
  map.number("recovery_per_s", out.recovery_per_s, {0, 1000, true, false, "over 0, up to 1000 per s"});
}
void read_identification(MapView& haptics, Identification& out) {
  const Entry e = haptics.entry("identification");
  MapView map(haptics.reader(), e.value, e.path, e.key_mark, {"enabled", "forgetting", "bound"});
  if (!map.valid()) return;
  map.boolean("enabled", out.enabled);
  map.number("forgetting", out.forgetting, {0.5, 1, true, false, "over 0.5, up to 1"});
  map.number("bound", out.bound, {0, 10, true, false, "over 0, up to 10 (a share: 0.25 is 25 %)"});
}
// haptics.design_hand: `none`, or {mass_kg, stiffness_n_per_m, damping_n_s_per_m} (each defaults
// to the project's default hand).
void read_design_hand(MapView& haptics, Haptics::DesignHand& out) {
  const Entry e = haptics.entry("design_hand");
  Reader& reader = haptics.reader();
  if (e.value.IsScalar()) {
    if (e.value.Scalar() == "none")
      out.enabled = false;
    else
      reader.error(e.value_mark, e.path,
                   "expected 'none' or a mapping {mass_kg: ..., stiffness_n_per_m: ..., damping_n_s_per_m: ...}, got " +
                       detail::describe_node(e.value));
    return;
  }
  MapView map(reader, e.value, e.path, e.key_mark, {"mass_kg", "stiffness_n_per_m", "damping_n_s_per_m"});
  if (!map.valid()) return;
  out.enabled = true;
  map.number("mass_kg", out.mass_kg, plausible::hand_mass_kg);
  map.number("stiffness_n_per_m", out.stiffness_n_per_m, plausible::hand_stiffness_n_per_m);
  map.number("damping_n_s_per_m", out.damping_n_s_per_m, plausible::hand_damping_n_s_per_m);
}

const Choices<DeviceType> kDevices{{"replay", DeviceType::replay},
                                   {"operator", DeviceType::operator_model},
                                   {"phantom", DeviceType::phantom},
                                   {"mouse", DeviceType::mouse}};
}  // namespace

// ---- solver and haptics -------------------------------------------------------------------------

void read_solver(MapView& scene, Solver& out) {
  const Entry e = scene.entry("solver");
  Reader& reader = scene.reader();
  MapView map(reader, e.value, e.path, e.key_mark,
              {"rate_hz", "newton", "linear_solver", "direct_max_dofs", "accuracy", "frame_newton_iterations"});
  if (!map.valid()) return;
  map.number("rate_hz", out.rate_hz, plausible::solver_rate_hz);
  map.choice("linear_solver", out.linear_solver, kLinearSolvers);
  map.integer("direct_max_dofs", out.direct_max_dofs, {1, 1e9});
  map.integer("frame_newton_iterations", out.frame_newton_iterations, {0, 1000});
  if (map.has("accuracy")) {
    const Entry a = map.entry("accuracy");
    if (a.value.IsScalar() && a.value.Scalar() == "none") {
      out.accuracy_position_m = out.accuracy_force_n = 0;
      out.accuracy_compliance = 1e-6;
    } else {
      MapView accuracy(reader, a.value, a.path, a.key_mark, {"position_m", "force_n", "compliance"});
      if (accuracy.valid()) {
        accuracy.number("position_m", out.accuracy_position_m, plausible::accuracy_position_m);
        accuracy.number("force_n", out.accuracy_force_n, plausible::accuracy_force_n);
        accuracy.number("compliance", out.accuracy_compliance, {1e-12, 0.1});
      }
    }
  }
  if (map.has("newton")) {
    const Entry n = map.entry("newton");
    MapView newton(reader, n.value, n.path, n.key_mark,
                   {"relative_tolerance", "absolute_tolerance", "max_iterations", "line_search",
                    "max_load_step_cuts"});
    if (!newton.valid()) return;
    newton.number("relative_tolerance", out.newton_relative_tolerance, {0, 1, true, true});
    newton.number("absolute_tolerance", out.newton_absolute_tolerance, plausible::newton_absolute_tolerance);
    newton.integer("max_iterations", out.newton_max_iterations, {1, 1000});
    newton.boolean("line_search", out.line_search);
    newton.integer("max_load_step_cuts", out.max_load_step_cuts, {0, 30});
  }
}

void read_haptics(MapView& scene, Haptics& out) {
  const Entry e = scene.entry("haptics");
  Reader& reader = scene.reader();
  MapView map(reader, e.value, e.path, e.key_mark,
              {"rate_hz", "local_model", "hold", "gains", "robustness_margin", "max_force_n",
               "max_force_rate_n_per_s", "watchdog_timeout_s", "coupling", "passivity", "identification",
               "design_hand"});
  if (!map.valid()) return;
  if (map.has("design_hand")) read_design_hand(map, out.design_hand);
  if (map.has("passivity")) read_passivity(map, out.passivity);
  if (map.has("identification")) read_identification(map, out.identification);
  map.boolean("coupling", out.coupling);
  map.number("rate_hz", out.rate_hz, plausible::haptic_rate_hz);
  map.choice("local_model", out.local_model, kLocalModels);
  map.choice("hold", out.hold, kHolds);
  map.number("robustness_margin", out.robustness_margin, {0, 1, false, true});
  map.number("max_force_n", out.max_force_n, plausible::max_force_n);
  map.number("max_force_rate_n_per_s", out.max_force_rate_n_per_s, plausible::max_force_rate_n_per_s);
  map.number("watchdog_timeout_s", out.watchdog_timeout_s, plausible::watchdog_timeout_s);
  if (!map.has("gains")) return;
  const Entry g = map.entry("gains");
  if (g.value.IsScalar()) {
    if (g.value.Scalar() != "auto")
      reader.error(g.value_mark, g.path,
                   "expected 'auto' or a mapping {proportional_n_per_m: ..., integral_n_per_m: ...}, "
                   "got " + detail::describe_node(g.value));
    return;
  }
  MapView gains(reader, g.value, g.path, g.key_mark, {"proportional_n_per_m", "integral_n_per_m"});
  if (!gains.valid()) return;
  out.automatic_gains = false;
  gains.number("proportional_n_per_m", out.proportional_n_per_m, plausible::gain_n_per_m, Need::required);
  const bool integral = out.local_model == LocalModelType::pi ||
                        out.local_model == LocalModelType::pi_smith;
  if (integral)
    gains.number("integral_n_per_m", out.integral_n_per_m, plausible::gain_n_per_m, Need::required);
  else
    reject_keys(gains, {"integral_n_per_m"},
                std::string("by local model ") + name_of(kLocalModels, out.local_model) +
                    " (only pi and pi_smith have an integral gain)");
}

// ---- probes -------------------------------------------------------------------------------------

namespace {

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

}  // namespace

namespace {

// A hardware device's workspace mapping and buttons: the axes must form a rotation (orthonormal,
// right-handed, to 1e-3), the buttons differ.
void read_workspace(MapView& device, Device& out) {
  Reader& reader = device.reader();
  if (device.has("workspace")) {
    const Entry w = device.entry("workspace");
    MapView map(reader, w.value, w.path, w.key_mark, {"x_axis", "y_axis", "z_axis", "scale", "offset_m"});
    if (map.valid()) {
      bool axes = map.vec3("x_axis", out.x_axis);
      axes = map.vec3("y_axis", out.y_axis) || axes;
      axes = map.vec3("z_axis", out.z_axis) || axes;
      const auto dot = [](const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
      const Vec3 &x = out.x_axis, &y = out.y_axis, &z = out.z_axis;
      const Vec3 cross{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
      double worst = 0;
      for (const auto& [a, b, want] : {std::tuple{x, x, 1.0}, {y, y, 1.0}, {z, z, 1.0}, {x, y, 0.0}, {y, z, 0.0}, {x, z, 0.0}})
        worst = std::max(worst, std::abs(dot(a, b) - want));
      if (axes && (!(worst <= 1e-3) || !(dot(cross, z) > 0)))
        reader.error(w.value_mark, w.path,
                     "x_axis, y_axis and z_axis are the device's axes in the scene frame: unit vectors at right "
                     "angles, right-handed (z = x cross y), each to 1e-3; these are not");
      map.number("scale", out.scale, plausible::workspace_scale);
      if (map.vec3("offset_m", out.offset_m))
        for (double c : out.offset_m)
          if (!plausible::workspace_offset_m.contains(c)) {
            const Entry o = map.entry("offset_m");
            reader.error(o.value_mark, o.path, "the offset must lie " + std::string(plausible::workspace_offset_m.why));
            break;
          }
    }
  }
  device.integer("engage_button", out.engage_button, plausible::device_button);
  device.integer("clutch_button", out.clutch_button, plausible::device_button);
  if (out.engage_button >= 0 && out.engage_button == out.clutch_button) {
    const Entry c = device.entry("clutch_button");
    reader.error(c.value_mark, c.path, "the clutch and engage buttons must differ (both are " +
                                            std::to_string(out.clutch_button) + ")");
  }
}

const Choices<HandEventType> kHandEvents{{"release", HandEventType::release},
                                         {"grip", HandEventType::grip},
                                         {"tremor", HandEventType::tremor},
                                         {"impact", HandEventType::impact}};

const Choices<HandKind> kHandKinds{{"one_mass", HandKind::one_mass}, {"stylus", HandKind::stylus}};

// hand.events: a list of {type, at_s, ...}; each type takes only its own keys.
void read_hand_events(MapView& hand, std::vector<HandEvent>& out) {
  const Entry e = hand.entry("events");
  Reader& reader = hand.reader();
  if (!e.value.IsSequence()) {
    reader.error(e.value_mark, e.path,
                 "expected a list of events (- {type: release, at_s: 1.2}), got " + detail::describe_node(e.value));
    return;
  }
  for (size_t i = 0; i < e.value.size(); ++i) {
    const YAML::Node item = e.value[i];
    MapView map(reader, item, e.path + "[" + std::to_string(i) + "]", item.Mark(),
                {"type", "at_s", "factor", "ramp_s", "frequency_hz", "amplitude_m", "speed_m_per_s", "direction"});
    if (!map.valid()) continue;
    HandEvent event;
    if (!map.choice("type", event.type, kHandEvents, Need::required)) continue;
    map.number("at_s", event.at_s, {0, 3600, false, false, "0 to 3600 s"}, Need::required);
    const std::string by = std::string("by a ") + name_of(kHandEvents, event.type) + " event";
    switch (event.type) {
      case HandEventType::release:
        reject_keys(map, {"factor", "ramp_s", "frequency_hz", "amplitude_m", "speed_m_per_s", "direction"}, by);
        break;
      case HandEventType::grip:
        reject_keys(map, {"frequency_hz", "amplitude_m", "speed_m_per_s", "direction"}, by);
        map.number("factor", event.factor, {0, 100, true, false, "over 0, up to 100"}, Need::required);
        map.number("ramp_s", event.ramp_s, {0, 10, false, false, "0 to 10 s"});
        break;
      case HandEventType::tremor:
        reject_keys(map, {"factor", "ramp_s", "speed_m_per_s"}, by);
        map.number("frequency_hz", event.frequency_hz, {0, 1000, true, false, "over 0, up to 1000 Hz"}, Need::required);
        map.number("amplitude_m", event.amplitude_m, {0, 0.05, false, false, "0 to 5 cm"}, Need::required);
        map.vec3("direction", event.direction);
        break;
      case HandEventType::impact:
        reject_keys(map, {"factor", "ramp_s", "frequency_hz", "amplitude_m"}, by);
        map.number("speed_m_per_s", event.speed_m_per_s, {0, 10, false, false, "0 to 10 m/s"}, Need::required);
        map.vec3("direction", event.direction);
        break;
    }
    if ((event.type == HandEventType::tremor || event.type == HandEventType::impact) && map.has("direction") &&
        event.direction[0] == 0 && event.direction[1] == 0 && event.direction[2] == 0)
      reader.error(map.entry("direction").value_mark, map.child_path("direction"), "a direction must not be zero");
    out.push_back(event);
  }
}

void read_device(MapView& probe, Device& out) {
  const Entry e = probe.entry("device");
  Reader& reader = probe.reader();
  MapView map(reader, e.value, e.path, e.key_mark,
              {"type", "trajectory", "hand", "name", "library", "workspace", "engage_button", "clutch_button"});
  if (!map.valid()) return;
  if (!map.choice("type", out.type, kDevices, Need::required)) return;
  const std::vector<std::string> trajectory_kinds{".csv", ".h5"};
  switch (out.type) {
    case DeviceType::replay:
      reject_keys(map, {"hand", "name"}, "by a replay device");
      map.existing_path("trajectory", out.trajectory, Need::required, trajectory_kinds);
      break;
    case DeviceType::operator_model: {
      reject_keys(map, {"name"}, "by a virtual operator");
      map.existing_path("trajectory", out.trajectory, Need::required, trajectory_kinds);
      if (!map.has("hand")) break;
      const Entry h = map.entry("hand");
      MapView hand(reader, h.value, h.path, h.key_mark,
                   {"model", "mass_kg", "stiffness_n_per_m", "damping_n_s_per_m", "handle_mass_kg",
                    "arm_stiffness_n_per_m", "arm_damping_n_s_per_m", "events"});
      if (!hand.valid()) break;
      // A stylus starts from its own defaults; a one-mass hand has no handle and no arm.
      if (hand.choice("model", out.hand.model, kHandKinds) && out.hand.model == HandKind::stylus) out.hand = HandModel::stylus();
      if (out.hand.model == HandKind::one_mass)
        reject_keys(hand, {"handle_mass_kg", "arm_stiffness_n_per_m", "arm_damping_n_s_per_m"}, "by a one-mass hand (model: stylus has them)");
      hand.number("handle_mass_kg", out.hand.handle_mass_kg, plausible::hand_mass_kg);
      hand.number("arm_stiffness_n_per_m", out.hand.arm_stiffness_n_per_m, plausible::hand_stiffness_n_per_m);
      hand.number("arm_damping_n_s_per_m", out.hand.arm_damping_n_s_per_m, plausible::hand_damping_n_s_per_m);
      hand.number("mass_kg", out.hand.mass_kg, plausible::hand_mass_kg);
      hand.number("stiffness_n_per_m", out.hand.stiffness_n_per_m, plausible::hand_stiffness_n_per_m);
      hand.number("damping_n_s_per_m", out.hand.damping_n_s_per_m, plausible::hand_damping_n_s_per_m);
      if (hand.has("events")) read_hand_events(hand, out.hand.events);
      break;
    }
    case DeviceType::phantom:
      reject_keys(map, {"trajectory", "hand"}, "by a PHANTOM device");
      map.text("name", out.phantom_name);
      map.text("library", out.library);
      read_workspace(map, out);
      break;
    case DeviceType::mouse:
      reject_keys(map, {"trajectory", "hand", "name", "library"}, "by the mouse");
      read_workspace(map, out);
      break;
  }
  if (out.type == DeviceType::replay || out.type == DeviceType::operator_model)
    reject_keys(map, {"library", "workspace", "engage_button", "clutch_button"}, "by a device without hardware");
}

}  // namespace

void read_probes(MapView& scene, std::vector<Probe>& out) {
  const Entry e = scene.entry("probes");
  Reader& reader = scene.reader();
  if (e.value.IsNull()) return;
  if (!e.value.IsSequence()) {
    reader.error(e.value_mark, e.path,
                 "expected a list of probes (- name: ..., device: ...), got " +
                     detail::describe_node(e.value));
    return;
  }
  if (e.value.size() > static_cast<size_t>(plausible::kMaxProbes)) {
    reader.error(e.value_mark, e.path,
                 std::to_string(e.value.size()) + " probes; a scene has at most " +
                     std::to_string(plausible::kMaxProbes) + " (one per hand at a trainer)");
    return;
  }
  std::set<std::string> names, phantoms;
  for (size_t i = 0; i < e.value.size(); ++i) {
    const YAML::Node item = e.value[i];
    MapView map(reader, item, e.path + "[" + std::to_string(i) + "]", item.Mark(),
                {"name", "device", "radius_m"});
    if (!map.valid()) continue;
    Probe probe;
    probe.where = {map.mark().line + 1, map.mark().column + 1};
    if (map.text("name", probe.name, Need::required)) {
      const Entry name = map.entry("name");
      if (!valid_name(probe.name))
        reader.error(name.value_mark, name.path,
                     "'" + probe.name + "' is not a valid probe name; use letters, digits, _ and -");
      else if (!names.insert(probe.name).second)
        reader.error(name.value_mark, name.path,
                     "probe name '" + probe.name + "' is used twice; probe names must be unique");
    }
    map.number("radius_m", probe.radius_m, plausible::probe_radius_m);
    map.require("device", "where the probe's positions come from");
    if (map.has("device")) read_device(map, probe.device);
    if (probe.device.type == DeviceType::phantom &&
        !phantoms.insert(probe.device.library + "\n" + probe.device.phantom_name).second) {
      const Entry d = map.entry("device");
      reader.error(d.value_mark, d.path,
                   "a second probe on " + (probe.device.phantom_name.empty() ? std::string("the default PHANTOM")
                                                                            : "the PHANTOM '" + probe.device.phantom_name + "'") +
                       "; each probe needs its own device (give each a device.name)");
    }
    out.push_back(probe);
  }
}

// ---- cross-field checks -------------------------------------------------------------------------

namespace {

void check_rates(MapView& scene, const Scene& s) {
  const double ratio = s.haptics.rate_hz / s.solver.rate_hz;
  const double whole = std::round(ratio);
  if (ratio >= 1 && std::abs(ratio - whole) <= 1e-9 * ratio) return;
  Entry where = scene.entry("solver");
  if (where.present && where.value.IsMap()) {
    MapView solver(scene.reader(), where.value, where.path, where.value_mark,
                   {"rate_hz", "newton", "linear_solver", "direct_max_dofs"});
    where = solver.entry("rate_hz");
    where.path = "solver.rate_hz";
  }
  scene.reader().error(where.value_mark, "solver.rate_hz",
                       "the haptic rate (" + format_number(s.haptics.rate_hz) +
                           " Hz) must be a whole multiple of the solver rate (" +
                           format_number(s.solver.rate_hz) + " Hz); " +
                           format_number(s.haptics.rate_hz / std::max(1.0, whole)) +
                           " Hz would give N = " + format_number(std::max(1.0, whole)));
}

}  // namespace

void check_cross_fields(MapView& scene, Scene& s) {
  Reader& reader = scene.reader();
  check_rates(scene, s);
  if (!s.probes.empty() && !s.effects.has(Effect::contact))
    reader.warning(scene.entry("effects").key_mark, "effects",
                   "probes are defined but 'contact' is not among the effects, so they will not "
                   "touch the tissue");
  const auto decoupled = [](const Material& m) {
    return m.model == MaterialModel::neo_hookean_incompressible || m.model == MaterialModel::mooney_rivlin;
  };
  bool all_decoupled = !s.material_given || decoupled(s.material);
  for (const RegionMaterial& m : s.materials) all_decoupled = all_decoupled && decoupled(m.material);
  if (s.effects.has(Effect::incompressibility) && !all_decoupled)
    reader.warning(scene.entry("effects").key_mark, "effects",
                   "incompressibility is meant for neo_hookean_incompressible or mooney_rivlin");
}

}  // namespace detail

using namespace detail;

const char* to_string(LinearSolver v) { return name_of(kLinearSolvers, v); }
const char* to_string(LocalModelType v) { return name_of(kLocalModels, v); }
const char* to_string(HoldType v) { return name_of(kHolds, v); }
const char* to_string(PassivityModeType v) { return name_of(kPassivityModes, v); }
const char* to_string(PassivityControllerType v) { return name_of(kPassivityControllers, v); }
const char* to_string(DeviceType v) { return name_of(kDevices, v); }

}  // namespace fetouch::config
