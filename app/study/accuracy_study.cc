// `fetouch study accuracy`: what accuracy costs in time. One knob turned at a time from the scene as
// it is (the baseline row): the mesh's element size, the element order, the Newton tolerance, the
// solver's rate (N ticks per frame) and the local model with its hold. Every configuration is a
// lockstep replay of the scene's trajectory (app/study/study_session.h), compared tick by tick with
// one reference the study computes: the finest mesh of the sweep, the scene's element order, Newton
// to 1e-10 with the accuracy policy off, the solver at the haptic rate (N = 1).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "app/chart_png.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/output_guard.h"
#include "app/progress.h"
#include "app/scene_devices.h"
#include "app/scene_mesh.h"
#include "app/study/study.h"
#include "app/session.h"
#include "app/study/study_session.h"
#include "haptics/local_model.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Configuration {
  std::string axis = "baseline";
  int level = 0;
  int order = 1;
  double tolerance = kNaN;  // NaN: the scene's own (with its accuracy policy)
  int ratio = 0;
  haptics::LocalModelKind model = haptics::LocalModelKind::pi;
  haptics::HoldKind hold = haptics::HoldKind::zoh;
  bool reference = false;
};

bool simplex(const config::Scene& scene) {
  return scene.mesh.element == config::ElementType::p1 || scene.mesh.element == config::ElementType::p2;
}
int scene_order(const config::Scene& scene) {
  return scene.mesh.element == config::ElementType::p2 || scene.mesh.element == config::ElementType::q2 ? 2 : 1;
}

// The scene as a configuration asks for it; its mesh made ready.
config::Scene configured(const config::Scene& base, const Configuration& c) {
  config::Scene scene = base;
  if (c.level != 0) {
    if (scene.mesh.source == config::MeshSource::generated) {
      scene.mesh.generated.refinements += c.level;
    } else {
      const double scale = std::pow(1.5, -c.level);
      scene.mesh.meshing.target_size_m *= scale;
      scene.mesh.meshing.refine_size_m *= scale;
    }
  }
  scene.mesh.element = simplex(base) ? (c.order == 2 ? config::ElementType::p2 : config::ElementType::p1)
                                     : (c.order == 2 ? config::ElementType::q2 : config::ElementType::q1);
  if (!std::isnan(c.tolerance)) {
    scene.solver.newton_relative_tolerance = c.tolerance;
    scene.solver.accuracy_position_m = 0, scene.solver.accuracy_force_n = 0;
    scene.solver.frame_newton_iterations = 0;
    if (c.reference) scene.solver.accuracy_compliance = 1e-12;
  }
  scene.solver.rate_hz = scene.haptics.rate_hz / c.ratio;
  scene.mesh = mesh_scene_volume(scene);
  return scene;
}

std::string describe(const Configuration& c) {
  std::ostringstream text;
  text << "level " << (c.level > 0 ? "+" : "") << c.level << ", P" << c.order << ", "
       << (std::isnan(c.tolerance) ? std::string("scene tolerance") : "tol " + format_number(c.tolerance)) << ", N = " << c.ratio
       << ", " << haptics::to_string(c.model) << "/" << haptics::to_string(c.hold);
  return text.str();
}

// Force errors of a run against the reference, per probe.
struct Errors {
  std::vector<double> rms_relative, peak_n, felt_relative;
};

double felt_at(const StudyRun& run, std::size_t probe, double time_s) {
  double felt = run.frames.empty() ? kNaN : run.frames.front().felt_n_per_m[probe];
  for (const StudyFrame& f : run.frames) {
    if (f.time_s > time_s + 1e-12) break;
    felt = f.felt_n_per_m[probe];
  }
  return felt;
}

Errors compare(const StudyRun& run, const StudyRun& reference) {
  Errors e;
  for (std::size_t p = 0; p < reference.forces.size(); ++p) {
    const auto& f = run.forces[p];
    const auto& g = reference.forces[p];
    double error2 = 0, reference2 = 0, peak = 0, peak_force = 0;
    std::size_t peak_tick = 0;
    for (std::size_t k = 0; k < std::min(f.size(), g.size()); ++k) {
      const double d = (f[k] - g[k]).norm();
      error2 += d * d, reference2 += g[k].squaredNorm(), peak = std::max(peak, d);
      if (g[k].norm() > peak_force) peak_force = g[k].norm(), peak_tick = k;
    }
    e.rms_relative.push_back(reference2 > 0 ? std::sqrt(error2 / reference2) : kNaN);
    e.peak_n.push_back(peak);
    const double t = static_cast<double>(peak_tick) * reference.period_s;
    const double k_ref = felt_at(reference, p, t), k = felt_at(run, p, t);
    e.felt_relative.push_back(peak_force > 0 ? std::abs(k - k_ref) / k_ref : kNaN);
  }
  return e;
}

double max_of(const std::vector<double>& v) {
  double m = kNaN;
  for (double x : v)
    if (!std::isnan(x)) m = std::isnan(m) ? x : std::max(m, x);
  return m;
}

}  // namespace

int run_study_accuracy(const AccuracyOptions& o) {
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  const config::Scene base = std::move(*loaded);
  if (base.probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes to replay\n";
    return kExitBadInput;
  }
  AccuracyOptions a = o;
  if (o.quick) {
    a.mesh_levels = {-1, 0}, a.orders = {}, a.tolerances = {1e-4}, a.ratios = {10, 50};
    a.models = {"p/zoh", "pi_smith/foh"};
    if (a.duration_s <= 0) a.duration_s = 1.0;
  }
  const haptics::HapticLoopSettings scene_loop = loop_settings(base);
  const bool file_mesh = base.mesh.source == config::MeshSource::file;
  Configuration baseline;
  baseline.order = scene_order(base), baseline.ratio = scene_loop.ratio;
  baseline.model = scene_loop.local_model, baseline.hold = scene_loop.hold;
  std::vector<Configuration> sweep{baseline};
  const auto add = [&sweep, &baseline](const char* axis, auto change) {
    Configuration c = baseline;
    c.axis = axis;
    change(c);
    for (const Configuration& s : sweep)  // the baseline's own value is its row
      if (s.level == c.level && s.order == c.order && s.ratio == c.ratio && s.model == c.model && s.hold == c.hold &&
          (s.tolerance == c.tolerance || (std::isnan(s.tolerance) && std::isnan(c.tolerance))))
        return;
    sweep.push_back(c);
  };
  int finest = 0;
  for (int level : a.mesh_levels) {
    if (file_mesh && level != 0) continue;
    if (base.mesh.source == config::MeshSource::generated && base.mesh.generated.refinements + level < 0) continue;
    finest = std::max(finest, level);
    add("mesh", [level](Configuration& c) { c.level = level; });
  }
  std::vector<int> orders = a.orders;
  if (orders.empty() && !o.quick) orders = {1, 2};
  for (int order : orders) add("order", [order](Configuration& c) { c.order = order; });
  for (double tolerance : a.tolerances) add("tolerance", [tolerance](Configuration& c) { c.tolerance = tolerance; });
  for (int ratio : a.ratios) add("rate", [ratio](Configuration& c) { c.ratio = ratio; });
  std::vector<std::string> models = a.models;
  if (models.empty())
    for (const char* m : {"p", "pi", "smith", "pi_smith"})
      for (const char* h : {"zoh", "foh"}) models.push_back(std::string(m) + "/" + h);
  for (const std::string& text : models) {
    const auto slash = text.find('/');
    haptics::LocalModelKind model{};
    if (slash == std::string::npos || !haptics::parse_local_model(text.substr(0, slash), model) ||
        (text.substr(slash + 1) != "zoh" && text.substr(slash + 1) != "foh")) {
      std::cerr << "error: --models: " << text << " is not MODEL/HOLD (MODEL p, pi, smith or pi_smith; HOLD zoh or foh)\n";
      return kExitBadInput;
    }
    const auto hold = text.substr(slash + 1) == "foh" ? haptics::HoldKind::foh : haptics::HoldKind::zoh;
    add("model", [model, hold](Configuration& c) { c.model = model, c.hold = hold; });
  }
  Configuration reference = baseline;
  reference.axis = "reference", reference.reference = true;
  reference.level = finest, reference.tolerance = 1e-10, reference.ratio = 1, reference.hold = haptics::HoldKind::zoh;

  const fs::path out(o.out);
  prepare_study_folder(out, o.scene, base);
  const long ticks = a.duration_s > 0 ? std::lround(a.duration_s * base.haptics.rate_hz) + 1 : -1;
  StudyRunSettings settings;
  settings.max_ticks = ticks, settings.threads = o.threads;
  // Each discretisation's own ideal (N = 1, Newton to 1e-10): the error a row adds by its solver
  // rate, tolerance and local model alone, beside its error against the one reference.
  std::map<std::pair<int, int>, StudyRun> ideals;
  for (const Configuration& c : sweep) ideals.emplace(std::make_pair(c.level, c.order), StudyRun{});
  Progress progress("study accuracy", static_cast<long>(sweep.size() + ideals.size()) + 1, std::cerr,
                    Progress::stderr_is_terminal());
  const auto run = [&](const Configuration& c) {
    log::info() << c.axis << ": " << describe(c);
    const config::Scene scene = configured(base, c);
    haptics::HapticLoopSettings loop = loop_settings(scene);
    loop.local_model = c.model, loop.hold = c.hold;
    return run_study_session(scene, loop, settings);
  };
  long done = 0;
  const StudyRun ref = run(reference);
  progress.update(++done);
  // The self-consistency check: the reference again, against itself (not with --quick: it costs
  // as much as the reference).
  double self_check = kNaN;
  if (!o.quick) {
    const StudyRun again = run(reference);
    self_check = max_of(compare(again, ref).rms_relative);
  }
  progress.update(++done);
  for (auto& [key, ideal] : ideals) {
    if (key == std::make_pair(reference.level, reference.order)) {
      ideal = ref;
      continue;
    }
    Configuration c = reference;
    c.level = key.first, c.order = key.second;
    try {
      ideal = run(c);
    } catch (const std::exception& e) {
      log::warning() << "not run: " << describe(c) << ": " << e.what();
    }
    progress.update(++done);
  }

  StudyTable table;
  table.columns = {"axis", "mesh_level", "cells", "dofs", "order", "newton_tolerance", "ratio", "local_model", "hold",
                   "frame_p50_ms", "frame_p99_ms", "frame_max_ms", "frame_budget_ms", "newton_per_frame", "newton_max",
                   "linear_per_frame", "cuts", "failed_frames", "force_rms_rel", "force_peak_n", "felt_stiffness_rel",
                   "force_rms_rel_own_ideal", "discretisation_rel", "within_budget"};
  for (const config::Probe& p : base.probes)
    for (const char* what : {"force_rms_rel_", "force_peak_n_", "felt_stiffness_rel_"}) table.columns.push_back(what + p.name);
  table.columns.push_back("pareto");
  std::vector<std::string> not_run;
  for (const Configuration& c : sweep) {
    StudyRun r;
    try {
      r = run(c);
    } catch (const std::exception& e) {  // a mesh too coarse for the probe's patch, say: the others still count
      not_run.push_back(describe(c) + ": " + e.what());
      log::warning() << "not run: " << not_run.back();
      progress.update(++done);
      continue;
    }
    progress.update(++done);
    const Errors e = compare(r, ref);
    const StudyRun& ideal = ideals.at(std::make_pair(c.level, c.order));
    const double own = ideal.forces.empty() ? kNaN : max_of(compare(r, ideal).rms_relative);
    // The discretisation's own error: its ideal against the reference (the same solver settings and
    // rate, a coarser mesh or another order), with nothing of the rate or the local model in it.
    const double discretisation = ideal.forces.empty() ? kNaN : max_of(compare(ideal, ref).rms_relative);
    std::vector<double> solve_ms;
    double newton = 0, linear = 0;
    int newton_max = 0, cuts = 0;
    for (const StudyFrame& f : r.frames) {
      solve_ms.push_back(1e3 * f.solve_s);
      newton += f.newton_iterations, linear += f.linear_iterations, cuts += f.cuts;
      newton_max = std::max(newton_max, f.newton_iterations);
    }
    const double frames = std::max<double>(1, static_cast<double>(r.frames.size()));
    std::vector<std::string> row = {c.axis, std::to_string(c.level), std::to_string(r.cells), std::to_string(r.dofs),
                                    std::to_string(c.order), format_number(c.tolerance), std::to_string(c.ratio),
                                    haptics::to_string(c.model), haptics::to_string(c.hold),
                                    format_number(percentile(solve_ms, 0.5)), format_number(percentile(solve_ms, 0.99)),
                                    format_number(percentile(solve_ms, 1)), format_number(1e3 * c.ratio * r.period_s),
                                    format_number(newton / frames), std::to_string(newton_max), format_number(linear / frames),
                                    std::to_string(cuts), std::to_string(r.newton_failures), format_number(max_of(e.rms_relative)),
                                    format_number(max_of(e.peak_n)), format_number(max_of(e.felt_relative)),
                                    format_number(own), format_number(discretisation),
                                    percentile(solve_ms, 0.99) <= 1e3 * c.ratio * r.period_s ? "1" : "0"};
    for (std::size_t p = 0; p < base.probes.size(); ++p)
      for (const double v : {e.rms_relative[p], e.peak_n[p], e.felt_relative[p]}) row.push_back(format_number(v));
    row.emplace_back();
    table.rows.push_back(std::move(row));
  }
  progress.finish();
  std::vector<double> cost, error;
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    cost.push_back(table.number(i, "frame_p99_ms"));
    error.push_back(table.number(i, "force_rms_rel"));
  }
  const std::vector<bool> pareto = pareto_optimal(cost, error);
  for (std::size_t i = 0; i < table.rows.size(); ++i) table.rows[i].back() = pareto[i] ? "1" : "0";

  AccuracyReference described;
  described.text = describe(reference);
  described.dofs = ref.dofs, described.cells = ref.cells, described.frames = static_cast<long>(ref.frames.size());
  described.ticks = ref.ticks, described.wall_s = ref.wall_s, described.self_check = self_check;
  std::vector<double> p99_ref;
  for (const StudyFrame& f : ref.frames) p99_ref.push_back(1e3 * f.solve_s);
  described.frame_p99_ms = percentile(p99_ref, 0.99);
  described.not_run = not_run;
  return write_accuracy_outputs(a, base, table, described);
}

}  // namespace fetouch::app
