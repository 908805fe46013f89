// `fetouch study passivity`: the loop with a hand in it. Every probe of the scene is held by the
// virtual operator (haptics/devices.h) following the probe's own trajectory; the study sweeps the
// hand (mass, grip stiffness, grip damping) and what the hand does (nothing, let go, tighten,
// tremble, strike) and runs each with the passivity layer off, on (the scene's default controller,
// `scaling`) and with plain Hannaford-Ryu, in lockstep. Each run is judged by one stated criterion
// (app/study/passivity_metrics.h); the nominal run (the default hand, no event) also gives the
// controller's share of ticks and the felt stiffness against the layer off.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>

#include "app/chart_png.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/output_guard.h"
#include "app/progress.h"
#include "app/scene_devices.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "app/session.h"
#include "app/study/passivity_metrics.h"
#include "app/study/study.h"
#include "haptics/stability_analysis.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct Hand {
  double mass_kg = 0, stiffness_n_per_m = 0, damping_n_s_per_m = 0;
  bool nominal = false;  // the scene's default hand (config::HandModel)
};

struct Run {
  std::string mode, event;
  Hand hand;
  Oscillation oscillation;
  double max_force_n = 0, felt_n_per_m = std::numeric_limits<double>::quiet_NaN();
  long ticks = 0, controller_ticks = 0, adjusting_ticks = 0, generation_events = 0, newton_failures = 0;
  double max_controller_force_n = 0, min_energy_j = 0, min_scale = 1;
  // The lifting with this run's hand in the loop (haptics/stability_analysis.h), at the stiffness,
  // gains and mode of the run's stiffest frame: the linear verdict the run is set against. The hand
  // as it starts (an event's change to it aside), the tissue's frame-rate damping left out (the
  // frames record none), every mode of the condensed stiffness with a hand on each contact.
  double lifted_radius = std::numeric_limits<double>::quiet_NaN();
  double stiffest_n_per_m = 0;  // the stiffest frame's largest condensed stiffness
  std::string error;            // a run that could not finish
  std::vector<double> force;    // device 0's force magnitude per tick (for the plot)
};

const char* const kModes[] = {"off", "on", "hannaford_ryu"};
const char* const kEvents[] = {"none", "release", "grip", "tremor8", "tremor10", "tremor12", "impact"};

void check_options(const PassivityOptions& o) {
  if (o.hand != "one_mass" && o.hand != "stylus") throw std::invalid_argument("--hand: unknown hand model '" + o.hand + "' (one_mass, stylus)");
  for (const std::string& m : o.modes)
    if (std::find(std::begin(kModes), std::end(kModes), m) == std::end(kModes))
      throw std::invalid_argument("--modes: unknown mode '" + m + "' (off, on, hannaford_ryu)");
  for (const std::string& e : o.events)
    if (std::find(std::begin(kEvents), std::end(kEvents), e) == std::end(kEvents))
      throw std::invalid_argument("--events: unknown event '" + e + "' (none, release, grip, tremor8, tremor10, tremor12, impact)");
  const auto positive = [](const std::vector<double>& values, const char* name, bool zero_ok) {
    for (double v : values)
      if (!std::isfinite(v) || v < 0 || (v == 0 && !zero_ok))
        throw std::invalid_argument(std::string(name) + ": " + std::to_string(v) + " is not " + (zero_ok ? "zero or more" : "positive"));
  };
  positive(o.masses, "--masses", false), positive(o.stiffnesses, "--stiffnesses", false), positive(o.dampings, "--dampings", true);
}

// The hand model's defaults: its handle and arm, and the nominal hand.
config::HandModel hand_defaults(const std::string& model) {
  return model == "stylus" ? config::HandModel::stylus() : config::HandModel{};
}

config::Scene with_hand(const config::Scene& base, const config::HandModel& model, const Hand& hand, const std::string& event,
                        double at_s, const config::Vec3& press, const std::string& mode) {
  config::Scene scene = base;
  for (config::Probe& p : scene.probes) {
    if (p.device.trajectory.empty())
      throw std::invalid_argument("probe '" + p.name + "' has no trajectory: the study's hand follows a probe's trajectory");
    p.device.type = config::DeviceType::operator_model;
    p.device.hand = model;
    p.device.hand.mass_kg = hand.mass_kg;
    p.device.hand.stiffness_n_per_m = hand.stiffness_n_per_m;
    p.device.hand.damping_n_s_per_m = hand.damping_n_s_per_m;
    p.device.hand.events.clear();
    if (event == "none") continue;
    config::HandEvent e;
    e.at_s = at_s, e.direction = press;
    if (event == "release") e.type = config::HandEventType::release;
    if (event == "grip") e.type = config::HandEventType::grip, e.factor = 3, e.ramp_s = 0.01;
    if (event.rfind("tremor", 0) == 0)
      e.type = config::HandEventType::tremor, e.frequency_hz = std::stod(event.substr(6)), e.amplitude_m = 5e-4;
    if (event == "impact") e.type = config::HandEventType::impact, e.speed_m_per_s = 0.2;
    p.device.hand.events.push_back(e);
  }
  config::Passivity& layer = scene.haptics.passivity;
  layer.mode = mode == "off" ? config::PassivityModeType::off : config::PassivityModeType::on;
  if (mode == "hannaford_ryu") layer.controller = config::PassivityControllerType::hannaford_ryu;
  return scene;
}

// Every device's forces judged (against its ideal when given); the run keeps the worst: an
// oscillating one first, then the longest ring.
Oscillation worst_oscillation(const std::vector<std::vector<Eigen::Vector3d>>& forces, double period_s, double clamp_n,
                              const std::vector<Oscillation>* ideal) {
  Oscillation worst;
  for (std::size_t d = 0; d < forces.size(); ++d) {
    std::vector<double> size;
    for (const Eigen::Vector3d& f : forces[d]) size.push_back(f.norm());
    Oscillation o = detect_oscillation(size, period_s, clamp_n);
    if (ideal && d < ideal->size()) o = judge_against_ideal(o, (*ideal)[d]);
    if (d == 0 || std::make_pair(o.oscillates, o.ringing_s) > std::make_pair(worst.oscillates, worst.ringing_s)) worst = o;
  }
  return worst;
}

// Each device's forces and positions per tick, for the study's nominal run.
struct Traces {
  std::vector<std::vector<Eigen::Vector3d>> forces, positions;
};

// `ideal`: when given, per device, the same hand and event on the ideal tissue (judge_against_ideal);
// `traces`: when given, filled with the run's forces and positions.
Run run_one(const config::Scene& scene, const Hand& hand, const std::string& event, const std::string& mode, long max_ticks,
            const std::vector<Oscillation>* ideal = nullptr, Traces* traces = nullptr) {
  Run r;
  r.mode = mode, r.event = event, r.hand = hand;
  try {
    const haptics::HapticLoopSettings loop = loop_settings(scene);
    SceneRig rig = build_scene_rig(scene, loop);
    SessionSettings session;
    session.loop = loop;
    session.probes = rig.probes;
    session.keep_forces = true;
    session.max_ticks = max_ticks;
    const SessionSummary s = run_lockstep(*rig.environment, rig.devices, session);
    r.ticks = s.ticks, r.max_force_n = s.max_force_n, r.newton_failures = s.newton_failures;
    r.oscillation = worst_oscillation(s.forces, loop.period_s, loop.safety.max_force_n, ideal);
    if (!s.forces.empty()) {
      r.felt_n_per_m = felt_stiffness(s.forces[0], s.positions[0]);
      for (const Eigen::Vector3d& f : s.forces[0]) r.force.push_back(f.norm());
    }
    if (traces) traces->forces = s.forces, traces->positions = s.positions;
    for (double k : s.stiffest_eigenvalues) r.stiffest_n_per_m = std::max(r.stiffest_n_per_m, k);
    if (!s.stiffest_eigenvalues.empty() && s.stiffest_local_model >= 0 && s.stiffest_hold >= 0 && !scene.probes.empty()) {
      haptics::LoopParameters p;
      p.local_model = static_cast<haptics::LocalModelKind>(s.stiffest_local_model);
      p.hold = static_cast<haptics::HoldKind>(s.stiffest_hold);
      p.ratio = loop.ratio;
      p.gains = {s.stiffest_proportional_gain, s.stiffest_integral_gain};
      p.hand = hand_parameters(scene.probes.front().device.hand);
      p.period_s = loop.period_s;
      double worst = 0;
      for (double k : s.stiffest_eigenvalues) {  // each mode of the condensed stiffness, a hand on each contact
        p.stiffness = Eigen::MatrixXd::Constant(1, 1, k);
        p.damping = Eigen::MatrixXd::Zero(1, 1);
        p.compliance = Eigen::MatrixXd::Constant(1, 1, 1 / k);
        worst = std::max(worst, haptics::analyse(p).spectral_radius);
      }
      r.lifted_radius = worst;
    }
    for (const PassivitySummary& p : s.passivity) {
      r.controller_ticks += p.controller_ticks, r.adjusting_ticks += p.adjusting_ticks, r.generation_events += p.generation_events;
      r.max_controller_force_n = std::max(r.max_controller_force_n, p.max_controller_force_n);
      r.min_energy_j = std::min(r.min_energy_j, p.min_energy_j), r.min_scale = std::min(r.min_scale, p.min_scale);
    }
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

std::string num(double x, const char* format = "%.3g") {
  if (!std::isfinite(x)) return "-";
  char text[48];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

std::string hand_text(const Hand& h) {
  return num(h.mass_kg) + " kg, " + num(h.stiffness_n_per_m) + " N/m, " + num(h.damping_n_s_per_m) + " N s/m";
}

// Totals of one mode over the box (the nominal runs apart).
struct ModeTotals {
  long runs = 0, oscillating = 0, failed = 0, controller_ticks = 0, adjusting_ticks = 0;
  double max_controller_force_n = 0;
  std::vector<double> felt_ratios;  // felt stiffness against the same run with the layer off
};

}  // namespace

int run_study_passivity(const PassivityOptions& o) {
  check_options(o);
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  config::Scene base = std::move(*loaded);
  if (base.probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes for a hand to hold\n";
    return kExitBadInput;
  }
  const fs::path out(o.out);
  prepare_study_folder(out, o.scene, base);
  base.mesh = mesh_scene_volume(base);
  const long max_ticks = o.duration_s > 0 ? std::lround(o.duration_s * base.haptics.rate_hz) + 1 : -1;

  std::vector<Hand> box;
  for (double m : o.masses)
    for (double k : o.stiffnesses)
      for (double b : o.dampings) box.push_back({m, k, b, false});
  const config::HandModel defaults = hand_defaults(o.hand);
  const Hand nominal{defaults.mass_kg, defaults.stiffness_n_per_m, defaults.damping_n_s_per_m, true};
  const long total = static_cast<long>(o.modes.size() * (1 + box.size() * o.events.size())) + 1;
  Progress progress("study passivity", total, std::cerr, Progress::stderr_is_terminal());
  long done = 0;

  // The nominal run with the layer off first: it places the events (the middle of probe 0's contact,
  // from its first touch to its last) and their direction (into the tissue, against the force there).
  std::vector<Run> runs;
  const config::Vec3 down{0, 0, -1};
  Traces traces;
  Run reference = run_one(with_hand(base, defaults, nominal, "none", 0, down, "off"), nominal, "none", "off", max_ticks, nullptr, &traces);
  progress.update(++done);
  if (!reference.error.empty()) throw std::runtime_error("the nominal run (the default hand, layer off) failed: " + reference.error);
  long first = -1, last = -1;
  for (long k = 0; k < static_cast<long>(reference.force.size()); ++k)
    if (reference.force[static_cast<std::size_t>(k)] > 0) {
      if (first < 0) first = k;
      last = k;
    }
  if (first < 0) throw std::runtime_error("the default hand never touched the tissue along the scene's trajectory: nothing to study");
  const double period = 1.0 / base.haptics.rate_hz;
  const double event_at = 0.5 * (first + last) * period;
  config::Vec3 press = down;
  const Eigen::Vector3d middle = traces.forces[0][static_cast<std::size_t>((first + last) / 2)];
  if (middle.norm() > 0) press = {-middle.x() / middle.norm(), -middle.y() / middle.norm(), -middle.z() / middle.norm()};
  log::info() << "study passivity: events at " << event_at << " s, along (" << press[0] << ", " << press[1] << ", " << press[2] << ")";

  // The ideal tissue for each device (passivity_metrics.h): where it first touched in the nominal
  // run, the stiffest frame's condensed stiffness. Each hand and event is played on it once, and
  // every mode's run is judged against it.
  const double clamp = base.haptics.max_force_n;
  std::vector<std::optional<IdealWall>> walls;
  for (std::size_t d = 0; d < traces.forces.size(); ++d)
    walls.push_back(wall_at_first_touch(traces.forces[d], traces.positions[d], reference.stiffest_n_per_m, clamp));
  std::map<std::tuple<std::string, double, double, double>, std::vector<Oscillation>> ideals;
  const auto ideal_of = [&](const Hand& h, const std::string& event) -> const std::vector<Oscillation>* {
    if (!(reference.stiffest_n_per_m > 0)) return nullptr;
    auto [at, fresh] = ideals.try_emplace({event, h.mass_kg, h.stiffness_n_per_m, h.damping_n_s_per_m});
    if (!fresh) return &at->second;
    const config::Scene scene = with_hand(base, defaults, h, event, event_at, press, "off");
    for (std::size_t d = 0; d < walls.size(); ++d) {
      Oscillation verdict;
      if (walls[d]) {
        const config::Probe& probe = scene.probes[d];
        verdict = detect_oscillation(ideal_wall_forces(probe_trajectory(probe, static_cast<int>(d)),
                                                       hand_parameters(probe.device.hand), hand_events(probe.device.hand),
                                                       *walls[d], period, max_ticks),
                                     period, clamp);
      }
      at->second.push_back(verdict);
    }
    return &at->second;
  };
  const std::vector<Oscillation>* nominal_ideal = ideal_of(nominal, "none");
  // The nominal run came before its walls did: judged again, against its ideal.
  if (nominal_ideal) reference.oscillation = worst_oscillation(traces.forces, period, clamp, nominal_ideal);

  for (const std::string& mode : o.modes) {
    runs.push_back(mode == "off" ? reference
                                 : run_one(with_hand(base, defaults, nominal, "none", 0, down, mode), nominal, "none", mode,
                                           max_ticks, nominal_ideal));
    progress.update(++done);
    for (const std::string& event : o.events)
      for (const Hand& h : box) {
        runs.push_back(run_one(with_hand(base, defaults, h, event, event_at, press, mode), h, event, mode, max_ticks, ideal_of(h, event)));
        runs.back().force.clear();  // the nominal runs' forces are plotted; the box's are summed up
        runs.back().force.shrink_to_fit();
        progress.update(++done);
      }
  }
  progress.finish();

  // The table: one row a run.
  StudyTable table;
  table.columns = {"mode", "event", "mass_kg", "stiffness_n_per_m", "damping_n_s_per_m", "nominal", "oscillates",
                   "ringing_s", "ringing_ptp_n", "chatter_ticks", "bounces", "ideal_bounces", "max_force_n", "felt_stiffness_n_per_m",
                   "controller_ticks", "controller_share", "adjusting_ticks", "max_controller_force_n", "generation_events",
                   "min_port_energy_j", "min_scale", "newton_failures", "lifted_radius_with_hand", "error"};
  std::map<std::string, ModeTotals> totals;
  std::map<std::tuple<std::string, double, double, double>, double> felt_off;  // (event, hand) -> felt, layer off
  for (const Run& r : runs)
    if (r.mode == "off" && !r.hand.nominal)
      felt_off[{r.event, r.hand.mass_kg, r.hand.stiffness_n_per_m, r.hand.damping_n_s_per_m}] = r.felt_n_per_m;
  std::map<std::pair<std::string, std::string>, ModeTotals> by_event;
  for (const Run& r : runs) {
    const double share = r.ticks > 0 ? static_cast<double>(r.controller_ticks) / r.ticks : 0;
    table.rows.push_back({r.mode, r.event, format_number(r.hand.mass_kg), format_number(r.hand.stiffness_n_per_m),
                          format_number(r.hand.damping_n_s_per_m), r.hand.nominal ? "1" : "0",
                          r.error.empty() ? (r.oscillation.oscillates ? "1" : "0") : "",
                          format_number(r.oscillation.ringing_s), format_number(r.oscillation.ringing_ptp_n),
                          std::to_string(r.oscillation.chatter_ticks), std::to_string(r.oscillation.bounces),
                          std::to_string(r.oscillation.ideal_bounces), format_number(r.max_force_n), format_number(r.felt_n_per_m),
                          std::to_string(r.controller_ticks), format_number(share), std::to_string(r.adjusting_ticks),
                          format_number(r.max_controller_force_n),
                          std::to_string(r.generation_events), format_number(r.min_energy_j), format_number(r.min_scale),
                          std::to_string(r.newton_failures), format_number(r.lifted_radius), r.error});
    if (r.hand.nominal) continue;
    for (ModeTotals* t : {&totals[r.mode], &by_event[{r.event, r.mode}]}) {
      ++t->runs;
      t->failed += !r.error.empty();
      t->oscillating += r.error.empty() && r.oscillation.oscillates;
      t->controller_ticks += r.controller_ticks, t->adjusting_ticks += r.adjusting_ticks;
      const auto off_felt = felt_off.find({r.event, r.hand.mass_kg, r.hand.stiffness_n_per_m, r.hand.damping_n_s_per_m});
      if (off_felt != felt_off.end() && std::isfinite(r.felt_n_per_m) && off_felt->second > 0)
        t->felt_ratios.push_back(r.felt_n_per_m / off_felt->second);
      t->max_controller_force_n = std::max(t->max_controller_force_n, r.max_controller_force_n);
    }
  }
  write_csv(table, out / "table.csv");

  const auto nominal_of = [&runs](const std::string& mode) -> const Run* {
    for (const Run& r : runs)
      if (r.hand.nominal && r.mode == mode) return &r;
    return nullptr;
  };
  const Run* off = nominal_of("off");
  const Run* on = nominal_of("on");
  const Run* hr = nominal_of("hannaford_ryu");
  const double on_share = on && on->ticks > 0 ? static_cast<double>(on->controller_ticks) / on->ticks : NAN;
  const double on_acting = on && on->ticks > 0 ? static_cast<double>(on->adjusting_ticks) / on->ticks : NAN;
  const double felt_ratio = on && off ? on->felt_n_per_m / off->felt_n_per_m : NAN;

  std::ostringstream md;
  md << "# Passivity study: " << base.name << "\n\nScene `" << o.scene << "`, lockstep, "
     << (o.duration_s > 0 ? "the trajectory's first " + num(o.duration_s) + " s" : "the whole trajectory")
     << ". Every probe is held by the virtual operator (docs/devices.md) along its own trajectory.\n\n"
     << "- Hands: masses " << o.masses.size() << ", grip stiffnesses " << o.stiffnesses.size() << ", dampings " << o.dampings.size()
     << " (" << box.size() << " hands), and the default hand (" << hand_text(nominal) << ") for the nominal run.\n"
     << (o.hand == "stylus" ? "- The hand is the two-stage stylus grip (Fu & Cavusoglu 2012): the masses are the hand's, the stiffnesses and "
                              "dampings the grip's; the handle " + num(defaults.handle_mass_kg) + " kg, the arm " +
                              num(defaults.arm_stiffness_n_per_m) + " N/m and " + num(defaults.arm_damping_n_s_per_m) + " N s/m.\n"
                            : std::string())
     << "- Events at " << num(event_at) << " s (the middle of the default hand's contact, first touch to last), along (" << num(press[0]) << ", "
     << num(press[1]) << ", " << num(press[2]) << ") (into the tissue): release; grip x3 in 10 ms; tremor 8, 10, 12 Hz of "
     << "0.5 mm; impact at 200 mm/s.\n"
     << "- Oscillates: the force's content above about 90 Hz (the force less its 11-tick moving average) swings over 0.1 N "
        "peak to peak, changing sign three times or more, in every 50 ms window for 0.3 s or more without halving, or the force jumps between 1 % and 99 % of the device's "
        "largest force within 5 ticks on 3 ticks or more, or the contact begins again within 0.25 s of its end and "
        "reaches 10 % of the device's largest force 3 times or more than the same hand and event do on the ideal tissue "
        "(bouncing; the ideal tissue: a flat elastic wall of the stiffest frame's condensed stiffness, "
     << num(reference.stiffest_n_per_m, "%.0f") << " N/m, where the default hand first touched, behind the same clamp, in "
        "continuous time: column ideal_bounces; app/study/passivity_metrics.h).\n\n"
     << "## Verdicts\n\n| mode | runs | oscillate | failed | ticks with a controller force | ticks the controller acted | "
        "largest controller force (N) | felt stiffness / off: median | below 10 % of off |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& mode : o.modes) {
    const ModeTotals& t = totals[mode];
    md << "| " << mode << " | " << t.runs << " | " << t.oscillating << " | " << t.failed << " | " << t.controller_ticks << " | "
       << t.adjusting_ticks << " | " << num(t.max_controller_force_n) << " | " << num(median(t.felt_ratios)) << " | "
       << std::count_if(t.felt_ratios.begin(), t.felt_ratios.end(), [](double x) { return x < 0.1; }) << " of " << t.felt_ratios.size()
       << " |\n";
  }
  md << "\nA controller force is the change the controller makes to what the device can be sent (both clamped to its largest "
        "force); the scaling controller keeps one on every tick its s is below 1, but acts only when s moves. The felt "
        "stiffness is the slope of force against depth over the first loading (20-80 % of the largest force), "
        "against the same hand and event with the layer off.\n";
  const ModeTotals& t_on = totals["on"];
  const ModeTotals& t_hr = totals["hannaford_ryu"];
  md << "\n- Nominal run (default hand, no event): with the layer on a controller force on " << num(100 * on_share, "%.2f")
     << " % of ticks, the controller acting on " << num(100 * on_acting, "%.2f") << " % (at most 2 % asked); felt stiffness " << (off ? num(off->felt_n_per_m, "%.1f") : "-") << " N/m off, "
     << (on ? num(on->felt_n_per_m, "%.1f") : "-") << " N/m on: ratio " << num(felt_ratio, "%.4f") << " (within 5 % asked)"
     << (hr ? ", " + num(hr->felt_n_per_m, "%.1f") + " N/m with Hannaford-Ryu" : std::string()) << ".\n";
  if (t_on.runs && t_hr.runs)
    md << "- Against Hannaford-Ryu over the box: ticks with a controller force " << t_on.controller_ticks << " against "
       << t_hr.controller_ticks << " (" << num(t_on.controller_ticks ? static_cast<double>(t_hr.controller_ticks) / t_on.controller_ticks : NAN)
       << "x fewer), ticks the controller acted " << t_on.adjusting_ticks << " against " << t_hr.adjusting_ticks << " ("
       << num(t_on.adjusting_ticks ? static_cast<double>(t_hr.adjusting_ticks) / t_on.adjusting_ticks : NAN) << "x fewer), "
       << "largest controller force " << num(t_on.max_controller_force_n) << " N against " << num(t_hr.max_controller_force_n) << " N ("
       << num(t_on.max_controller_force_n > 0 ? t_hr.max_controller_force_n / t_on.max_controller_force_n : NAN) << "x lower).\n";
  // The linear verdict against the runs with the layer off and no event (each hand once).
  {
    long said_rings = 0, rang = 0, said_stable = 0, rang_anyway = 0;
    for (const Run& r : runs) {
      if (r.mode != "off" || r.event != "none" || r.hand.nominal || !r.error.empty() || !std::isfinite(r.lifted_radius)) continue;
      if (r.lifted_radius >= 1)
        ++said_rings, rang += r.oscillation.oscillates;
      else
        ++said_stable, rang_anyway += r.oscillation.oscillates;
    }
    if (said_rings + said_stable > 0)
      md << "- The lifting with the hand in the loop (haptics/stability_analysis.h; at the stiffness, gains and mode of each run's "
            "stiffest frame, the hand linearised in contact), against the runs with the layer off and no event: it calls "
         << said_rings << " of " << said_rings + said_stable << " hands unstable, of which " << rang << " oscillated; of the "
         << said_stable << " it calls stable, " << rang_anyway << " oscillated. The nominal hand: radius "
         << (off ? num(off->lifted_radius, "%.3f") : "-") << ".\n";
  }
  md << "\n## By event\n\n| event |";
  for (const std::string& mode : o.modes) md << " " << mode << ": oscillate / runs |";
  md << "\n|---|";
  for (std::size_t i = 0; i < o.modes.size(); ++i) md << "---|";
  md << "\n";
  Chart bars;
  bars.title = "Runs that oscillate, by event", bars.x_label = "event", bars.y_label = "runs that oscillate", bars.height = 600;
  const std::array<unsigned char, 3> colors[] = {{200, 60, 40}, {40, 120, 200}, {120, 120, 120}};
  for (std::size_t m = 0; m < o.modes.size(); ++m) bars.series.push_back({o.modes[m], {}, {}, colors[m % 3], false, 2, true});
  for (const std::string& event : o.events) {
    md << "| " << event << " |";
    for (std::size_t m = 0; m < o.modes.size(); ++m) {
      const ModeTotals& t = by_event[{event, o.modes[m]}];
      md << " " << t.oscillating << " / " << t.runs << " |";
      bars.series[m].x.push_back(static_cast<double>(bars.x_ticks.size()));
      bars.series[m].y.push_back(static_cast<double>(t.oscillating));
    }
    bars.x_ticks.push_back(event);
    md << "\n";
  }
  md << "\n## Runs that oscillate with the layer on\n\n";
  long listed = 0;
  for (const Run& r : runs)
    if (r.mode == "on" && (r.oscillation.oscillates || !r.error.empty()) && listed++ < 40)
      md << "- " << r.event << ", " << hand_text(r.hand) << ": "
         << (r.error.empty() ? "ringing " + num(r.oscillation.ringing_s) + " s (" + num(r.oscillation.ringing_ptp_n) + " N), chatter " +
                                   std::to_string(r.oscillation.chatter_ticks) + " ticks, bounces " +
                                   std::to_string(r.oscillation.bounces) + " (the ideal tissue " +
                                   std::to_string(r.oscillation.ideal_bounces) + ")"
                             : "failed: " + r.error)
         << "\n";
  if (listed == 0) md << "None.\n";
  // The nominal runs' forces, one curve a mode.
  Chart curves;
  curves.title = "The nominal run: force on the hand", curves.x_label = "time (s)", curves.y_label = "force (N)", curves.height = 600;
  for (std::size_t m = 0; m < o.modes.size(); ++m)
    if (const Run* r = nominal_of(o.modes[m])) {
      ChartSeries s{o.modes[m], {}, {}, colors[m % 3]};
      for (std::size_t k = 0; k < r->force.size(); ++k) s.x.push_back(k * period), s.y.push_back(r->force[k]);
      curves.series.push_back(std::move(s));
    }
  if (display_available()) {
    write_chart_png(bars, out / "oscillating.png");
    write_chart_png(curves, out / "nominal_force.png");
    md << "\n![oscillating runs](oscillating.png)\n\n![nominal force](nominal_force.png)\n";
  } else {
    log::warning() << no_display_hint(out / "oscillating.png");
    md << "\nNot drawn: " << no_display_hint(out / "oscillating.png") << ".\n";
  }
  write_text_file(out / "report.md", md.str());

  std::ostringstream json_text;
  JsonWriter json(json_text);
  json.begin_object().key("scene").value(base.name).key("hands").value(static_cast<long>(box.size()))
      .key("event_at_s").value(event_at).key("modes").begin_object();
  for (const std::string& mode : o.modes) {
    const ModeTotals& t = totals[mode];
    json.key(mode).begin_object().key("runs").value(t.runs).key("oscillating").value(t.oscillating).key("failed").value(t.failed)
        .key("controller_ticks").value(t.controller_ticks).key("adjusting_ticks").value(t.adjusting_ticks)
        .key("max_controller_force_n").value(t.max_controller_force_n).key("felt_ratio_median").value(median(t.felt_ratios)).end_object();
  }
  json.end_object().key("nominal").begin_object().key("controller_share_on").value(on_share).key("acting_share_on").value(on_acting)
      .key("felt_stiffness_off_n_per_m").value(off ? off->felt_n_per_m : NAN)
      .key("felt_stiffness_on_n_per_m").value(on ? on->felt_n_per_m : NAN).key("felt_ratio").value(felt_ratio).end_object()
      .end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), o.json)) {
    std::printf("%-15s %6s %10s %7s %17s %14s %22s %12s\n", "mode", "runs", "oscillate", "failed", "controller ticks", "acting ticks",
                "largest controller (N)", "felt / off");
    for (const std::string& mode : o.modes) {
      const ModeTotals& t = totals[mode];
      std::printf("%-15s %6ld %10ld %7ld %17ld %14ld %22.3f %12.3f\n", mode.c_str(), t.runs, t.oscillating, t.failed, t.controller_ticks,
                  t.adjusting_ticks, t.max_controller_force_n, median(t.felt_ratios));
    }
    std::printf("nominal: a controller force on %.2f %% of ticks, acting on %.2f %%, felt stiffness on/off %.4f; wrote %s and %s\n",
                100 * on_share, 100 * on_acting, felt_ratio,
                (out / "table.csv").string().c_str(), (out / "report.md").string().c_str());
  }
  return kExitOk;
}

}  // namespace fetouch::app
