// `fetouch study effects`: what each effect of a scene costs. The scene's session as it is (twice:
// the second run measures the noise), then with each listed effect removed in turn; each run's frame
// times and each term's own time per frame (its assembly, and for a cavity its own solves). An
// effect the scene does not list has no term: the profile shows none, and gravity's own counter
// (fem::gravity_evaluations) shows its code never ran.
//
// Removing an effect changes the physics, and with it the Newton work a frame takes. So beside the
// time saved over all frames the study compares like with like: the frames in which both runs did
// the same work (Newton and linear iterations besides the removed term's own, cuts, no
// factorisation, the same compliance work). There a removal saves exactly its term's own time, up
// to the noise; what it saves or costs beyond that is the Newton work the physics change brings.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <sstream>
#include <tuple>

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
#include "fem/tissue_model.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;
using config::Effect;

// The term an effect builds (the solver's profile names terms, not effects).
const char* term_of(Effect e) {
  switch (e) {
    case Effect::elasticity: return "elasticity";
    case Effect::gravity: return "loads";
    case Effect::inertia: return "inertia";
    case Effect::damping: return "damping";
    case Effect::incompressibility: return "elasticity";
    case Effect::cavity: return "cavity";
    case Effect::contact: return "contact";
  }
  return "";
}

struct EffectRun {
  std::string name;                // "as is", "as is (again)", "without gravity", ...
  std::vector<std::string> gone;   // the terms the run lacks that the scene as is has
  StudyRun run;
  long gravity_calls = 0;
  double mean_ms = 0, p50_ms = 0, p99_ms = 0, newton = 0, linear = 0;
};

// A term's own time in a frame, or summed over a run, s.
const StudyTermTime* find_term(const std::vector<StudyTermTime>& terms, const std::string& name) {
  for (const StudyTermTime& t : terms)
    if (t.name == name) return &t;
  return nullptr;
}

double own_ms_per_frame(const StudyRun& r, const std::string& term, bool assembly_only = false) {
  const StudyTermTime* t = find_term(r.terms, term);
  if (!t) return 0;
  return 1e3 * (assembly_only ? t->assembly_s : t->own_s()) / std::max<double>(1, static_cast<double>(r.frames.size()));
}

// The frames in which runs `a` (the scene as is) and `b` did the same work but the own work of the
// terms `gone`, which `b` lacks: the time saved there, the terms' own time there, and the standard
// error of the per-frame difference between the two.
struct EqualWork {
  int frames = 0;
  double saved_ms = 0, own_ms = 0, standard_error_ms = 0;
  double frame_ms = 0;  // the scene as is, over those frames
};

// The work a frame did: Newton and linear iterations (less `own_linear`, a removed term's own),
// cuts, factorisations (taken, waited for, under way in the background) and the compliance's work.
auto work(const StudyFrame& f, long own_linear = 0) {
  return std::make_tuple(f.converged, f.background, f.newton_iterations, f.cuts, f.linear_iterations - own_linear,
                         f.factorisations, f.factorisation_s == 0, f.compliance_linear_iterations,
                         f.compliance_factorisations, f.compliance_refined);
}

// Two frames did the same work, but `a_own_linear` linear iterations of a's own terms, and a quiet
// one: converged, no factorisation, none under way in the background (the worker shares the
// machine's cores and memory).
bool same_work(const StudyFrame& a, const StudyFrame& b, long a_own_linear = 0) {
  return work(a, a_own_linear) == work(b) && a.converged && !a.background && a.factorisations == 0 &&
         a.factorisation_s == 0 && a.compliance_factorisations == 0;
}

// `run` and `again` are runs of the same configuration: each frame of `run` takes the time (and
// the terms' own times) of the faster of the two where both did exactly the same work.
void keep_fastest(StudyRun& run, const StudyRun& again) {
  for (std::size_t i = 0; i < std::min(run.frames.size(), again.frames.size()); ++i) {
    StudyFrame& f = run.frames[i];
    const StudyFrame& g = again.frames[i];
    if (work(f) != work(g)) continue;
    f.solve_s = std::min(f.solve_s, g.solve_s);
    for (StudyTermTime& t : f.terms)
      if (const StudyTermTime* u = find_term(g.terms, t.name))
        t.assembly_s = std::min(t.assembly_s, u->assembly_s), t.other_s = std::min(t.other_s, u->other_s);
  }
  for (StudyTermTime& total : run.terms) {  // the run's totals, from its frames
    total.assembly_s = total.other_s = 0;
    for (const StudyFrame& f : run.frames)
      if (const StudyTermTime* t = find_term(f.terms, total.name)) total.assembly_s += t->assembly_s, total.other_s += t->other_s;
  }
}

EqualWork equal_work(const StudyRun& a, const StudyRun& b, const std::vector<std::string>& gone) {
  std::vector<double> saved, own;
  double frame_ms = 0;
  for (std::size_t i = 0; i < std::min(a.frames.size(), b.frames.size()); ++i) {
    const StudyFrame &fa = a.frames[i], &fb = b.frames[i];
    double own_s = 0;
    long own_linear = 0;
    for (const std::string& name : gone)
      if (const StudyTermTime* t = find_term(fa.terms, name)) own_s += t->own_s(), own_linear += t->linear_iterations;
    if (!same_work(fa, fb, own_linear)) continue;
    saved.push_back(1e3 * (fa.solve_s - fb.solve_s));
    frame_ms += 1e3 * fa.solve_s;
    own.push_back(1e3 * own_s);
  }
  EqualWork w;
  w.frames = static_cast<int>(saved.size());
  if (saved.empty()) return w;
  const double n = static_cast<double>(saved.size());
  w.saved_ms = std::accumulate(saved.begin(), saved.end(), 0.0) / n;
  w.frame_ms = frame_ms / n;
  w.own_ms = std::accumulate(own.begin(), own.end(), 0.0) / n;
  double spread = 0;
  for (std::size_t i = 0; i < saved.size(); ++i) spread += std::pow(saved[i] - own[i] - (w.saved_ms - w.own_ms), 2);
  w.standard_error_ms = saved.size() > 1 ? std::sqrt(spread / (n - 1) / n) : 0;
  return w;
}

// Holds: at equal work the removal saved its terms' own time, within the largest of three times the
// noise (the scene against itself at equal work, one sample of it), twice the standard error of the
// per-frame difference, and 2 % of the frame (two runs of one scene on a shared machine: their mean
// frame times were seen to differ by 0.1 % to 8 %, most often 0.5 % to 2 %).
double equal_work_tolerance(const EqualWork& w, double noise_ms) {
  return std::max({3 * noise_ms, 2 * w.standard_error_ms, 0.02 * w.frame_ms});
}
bool equal_work_holds(const EqualWork& w, double noise_ms) {
  return w.frames > 0 && std::abs(w.saved_ms - w.own_ms) <= equal_work_tolerance(w, noise_ms);
}

std::string ms(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", x);
  return text;
}

// Every frame of every run, for whoever wants to fit their own model: OUT/frames.csv.
void write_frames(const std::vector<EffectRun>& runs, const std::vector<std::string>& terms, const fs::path& file) {
  StudyTable t;
  t.columns = {"run", "frame", "converged", "solve_ms", "newton", "linear", "cuts", "factorisations", "background", "assembly_ms", "factorisation_ms",
               "linear_solve_ms", "compliance_ms", "compliance_linear", "compliance_factorisations", "compliance_refined"};
  for (const std::string& term : terms) t.columns.push_back("own_ms_" + term), t.columns.push_back("own_linear_" + term);
  for (const EffectRun& r : runs)
    for (std::size_t i = 0; i < r.run.frames.size(); ++i) {
      const StudyFrame& f = r.run.frames[i];
      std::vector<std::string> row = {r.name, std::to_string(i), f.converged ? "1" : "0", format_number(1e3 * f.solve_s), std::to_string(f.newton_iterations),
                                      std::to_string(f.linear_iterations), std::to_string(f.cuts), std::to_string(f.factorisations), f.background ? "1" : "0",
                                      format_number(1e3 * f.assembly_s), format_number(1e3 * f.factorisation_s),
                                      format_number(1e3 * f.linear_solve_s), format_number(1e3 * f.compliance_s),
                                      std::to_string(f.compliance_linear_iterations), std::to_string(f.compliance_factorisations),
                                      f.compliance_refined ? "1" : "0"};
      for (const std::string& term : terms) {
        const StudyTermTime* own = find_term(f.terms, term);
        row.push_back(format_number(own ? 1e3 * own->own_s() : 0));
        row.push_back(std::to_string(own ? own->linear_iterations : 0));
      }
      t.rows.push_back(std::move(row));
    }
  write_csv(t, file);
}

}  // namespace

int run_study_effects(const EffectsOptions& o) {
  std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
  if (!loaded) return kExitBadInput;
  config::Scene base = std::move(*loaded);
  if (base.probes.empty()) {
    std::cerr << "error: " << o.scene << ": the scene has no probes to replay\n";
    return kExitBadInput;
  }
  const fs::path out(o.out);
  prepare_study_folder(out, o.scene, base);
  base.mesh = mesh_scene_volume(base);
  const double duration = o.quick && o.duration_s <= 0 ? 1.0 : o.duration_s;
  StudyRunSettings settings;
  settings.max_ticks = duration > 0 ? std::lround(duration * base.haptics.rate_hz) + 1 : -1;
  settings.threads = o.threads;

  // What can be taken away: every listed effect but elasticity (always simulated) and contact (the
  // probes load the tissue through it); inertia takes damping with it (damping acts on the motion).
  std::vector<std::pair<std::string, std::vector<Effect>>> removals;
  for (Effect e : base.effects.listed) {
    if (e == Effect::elasticity || e == Effect::contact) continue;
    std::vector<Effect> gone{e};
    if (e == Effect::inertia && base.effects.has(Effect::damping)) gone.push_back(Effect::damping);
    removals.emplace_back(std::string("without ") + config::to_string(e) + (gone.size() > 1 ? " (and damping)" : ""), gone);
  }
  // The configurations, run round-robin `repeat` times (a slow spell of the machine then falls on
  // every configuration alike), each frame keeping its fastest time.
  std::vector<std::pair<std::string, config::Scene>> configurations = {{"as is", base}, {"as is (again)", base}};
  for (const auto& [name, gone] : removals) {
    config::Scene scene = base;
    auto& listed = scene.effects.listed;
    for (Effect e : gone) listed.erase(std::remove(listed.begin(), listed.end(), e), listed.end());
    configurations.emplace_back(name, std::move(scene));
  }
  std::vector<EffectRun> runs(configurations.size());
  Progress progress("study effects", static_cast<long>(configurations.size()) * o.repeat, std::cerr,
                    Progress::stderr_is_terminal());
  for (int k = 0; k < o.repeat; ++k)
    for (std::size_t c = 0; c < configurations.size(); ++c) {
      const auto& [name, scene] = configurations[c];
      log::info() << "study effects: " << name << " (run " << k + 1 << " of " << o.repeat << ")";
      const long before = fem::gravity_evaluations();
      StudyRun run = run_study_session(scene, loop_settings(scene), settings);
      if (k == 0) {
        runs[c].name = name, runs[c].run = std::move(run);
        runs[c].gravity_calls = fem::gravity_evaluations() - before;
      } else {
        keep_fastest(runs[c].run, run);
      }
      progress.update(static_cast<long>(k * configurations.size() + c + 1));
    }
  for (EffectRun& r : runs) {
    std::vector<double> times;
    for (const StudyFrame& f : r.run.frames)
      times.push_back(1e3 * f.solve_s), r.newton += f.newton_iterations, r.linear += f.linear_iterations;
    const double frames = std::max<double>(1, static_cast<double>(times.size()));
    r.mean_ms = std::accumulate(times.begin(), times.end(), 0.0) / frames;
    r.p50_ms = percentile(times, 0.5), r.p99_ms = percentile(times, 0.99), r.newton /= frames, r.linear /= frames;
    // The terms the removal takes away (a term another listed effect still builds stays).
    for (const StudyTermTime& t : runs.front().run.terms)
      if (!find_term(r.run.terms, t.name)) r.gone.push_back(t.name);
  }
  progress.finish();

  // Every term any run built; the noise; each removal at equal work.
  std::vector<std::string> terms;
  for (const EffectRun& r : runs)
    for (const StudyTermTime& t : r.run.terms)
      if (std::find(terms.begin(), terms.end(), t.name) == terms.end()) terms.push_back(t.name);
  const EffectRun& full = runs[0];
  const double noise = std::abs(runs[0].mean_ms - runs[1].mean_ms);
  std::vector<EqualWork> equal;
  for (const EffectRun& r : runs) equal.push_back(equal_work(full.run, r.run, r.gone));
  const double noise_equal = std::abs(equal[1].saved_ms);

  StudyTable table;
  table.columns = {"run", "frame_mean_ms", "frame_p50_ms", "frame_p99_ms", "newton_per_frame", "linear_per_frame",
                   "gravity_evaluations", "removed_terms", "saved_ms", "equal_work_frames", "equal_work_saved_ms",
                   "equal_work_own_ms", "equal_work_tolerance_ms", "equal_work_holds"};
  for (const std::string& t : terms) table.columns.push_back("assembly_ms_" + t), table.columns.push_back("own_ms_" + t);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const EffectRun& r = runs[i];
    std::string gone;
    for (const std::string& t : r.gone) gone += (gone.empty() ? "" : " ") + t;
    const bool removal = i >= 2;
    std::vector<std::string> row = {r.name, format_number(r.mean_ms), format_number(r.p50_ms), format_number(r.p99_ms),
                                    format_number(r.newton), format_number(r.linear), std::to_string(r.gravity_calls), gone,
                                    i == 0 ? "" : format_number(full.mean_ms - r.mean_ms),
                                    i == 0 ? "" : std::to_string(equal[i].frames),
                                    i == 0 ? "" : format_number(equal[i].saved_ms), i == 0 ? "" : format_number(equal[i].own_ms),
                                    removal ? format_number(equal_work_tolerance(equal[i], noise_equal)) : "",
                                    removal ? (equal_work_holds(equal[i], noise_equal) ? "1" : "0") : ""};
    for (const std::string& t : terms)
      row.push_back(format_number(own_ms_per_frame(r.run, t, true))), row.push_back(format_number(own_ms_per_frame(r.run, t)));
    table.rows.push_back(std::move(row));
  }
  write_csv(table, out / "table.csv");
  write_frames(runs, terms, out / "frames.csv");

  std::ostringstream md;
  md << "# Effects study: " << base.name << "\n\nScene `" << o.scene << "`; "
     << (duration > 0 ? "the trajectory's first " + ms(duration) + " s" : "the whole trajectory") << ", lockstep, "
     << full.run.frames.size() << " frames a run, " << full.run.dofs << " DOFs, " << o.threads << " assembly thread(s).\n\n"
     << "## Runs\n\nEach term's own time: its assembly, and for a term with an unknown of its own (a cavity's pressure) "
        "its own solves too.\n\n| run | frame mean (ms) | p50 | p99 | Newton / frame | linear / frame |";
  for (const std::string& t : terms) md << " " << t << " (ms / frame) |";
  md << "\n|---|---|---|---|---|---|";
  for (std::size_t i = 0; i < terms.size(); ++i) md << "---|";
  md << "\n";
  for (const EffectRun& r : runs) {
    md << "| " << r.name << " | " << ms(r.mean_ms) << " | " << ms(r.p50_ms) << " | " << ms(r.p99_ms) << " | " << ms(r.newton)
       << " | " << ms(r.linear) << " |";
    for (const std::string& t : terms) md << " " << ms(own_ms_per_frame(r.run, t)) << " |";
    md << "\n";
  }
  md << "\nNoise: the same scene twice differs by " << ms(noise) << " ms in its mean frame time (" << ms(noise_equal)
     << " ms over the " << equal[1].frames << " frames in which both did the same work).\n\n"
     << "## What each listed effect costs\n\n| effect | its term | term's own time (ms / frame) | share of the frame | "
        "frame time saved by removing it (ms) | share saved | Newton / frame as is, without |\n|---|---|---|---|---|---|---|\n";
  Chart bars;
  bars.title = "What each effect costs a frame (" + base.name + ")";
  bars.x_label = "effect", bars.y_label = "ms per frame";
  ChartSeries term_bars{"its term's own time", {}, {}, {40, 100, 200}, false, 2, true};
  ChartSeries saved_bars{"time saved without it", {}, {}, {220, 110, 30}, false, 2, true};
  ChartSeries own_equal_bars{"its term's own time, frames of equal work", {}, {}, {130, 80, 180}, false, 2, true};
  ChartSeries equal_bars{"time saved there", {}, {}, {60, 160, 60}, false, 2, true};
  for (Effect e : base.effects.listed) {
    const std::string name = config::to_string(e);
    const double term_ms = own_ms_per_frame(full.run, term_of(e));
    std::string saved = "-", saved_share = "not removable", newton = "-";
    double saved_ms = 0, equal_ms = 0, own_equal_ms = 0;
    for (std::size_t i = 0; i < removals.size(); ++i)
      if (removals[i].second.front() == e) {
        const EffectRun& r = runs[i + 2];
        saved_ms = full.mean_ms - r.mean_ms, equal_ms = equal[i + 2].saved_ms, own_equal_ms = equal[i + 2].own_ms;
        saved = ms(saved_ms), saved_share = ms(100 * saved_ms / full.mean_ms) + " %";
        newton = ms(full.newton) + ", " + ms(r.newton);
      }
    if (e == Effect::elasticity) saved_share = "always simulated";
    if (e == Effect::contact) saved_share = "the probes touch through it";
    md << "| " << name << " | " << term_of(e) << " | " << ms(term_ms) << " | " << ms(100 * term_ms / full.mean_ms) << " % | "
       << saved << " | " << saved_share << " | " << newton << " |\n";
    bars.x_ticks.push_back(name);
    const double x = static_cast<double>(bars.x_ticks.size() - 1);
    term_bars.x.push_back(x), term_bars.y.push_back(term_ms);
    saved_bars.x.push_back(x), saved_bars.y.push_back(std::max(0.0, saved_ms));
    own_equal_bars.x.push_back(x), own_equal_bars.y.push_back(own_equal_ms);
    equal_bars.x.push_back(x), equal_bars.y.push_back(std::max(0.0, equal_ms));
  }
  md << "\nRemoving an effect changes the physics, and with it the Newton work a frame takes (a load that is no "
        "longer there, a time step that no longer damps): over all frames the time saved is the term's own time plus "
        "that change in work, which can be larger or even negative.\n\n## At equal work\n\n"
        "The frames in which the run without the effect did the same work as the scene as is (the same Newton and "
        "linear iterations besides the removed term's own, the same cuts, no factorisation and none under way in "
        "the background, the same compliance work). There the time saved should be the removed term's own time; it holds when the two agree within the "
        "largest of three times the noise at equal work (a single sample of it), twice the standard error of their "
        "per-frame difference, and 2 % of the frame time there (the drift of two runs' timings on a shared machine). "
        "Every configuration is run round-robin " + std::to_string(o.repeat) + " time(s), each frame keeping its fastest "
        "time where the runs did exactly the same work.\n\n"
        "| removal | terms removed | frames of equal work | time saved there (ms / frame) | removed terms' own time "
        "there | difference | tolerance | holds |\n|---|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 2; i < runs.size(); ++i) {
    const EqualWork& w = equal[i];
    std::string gone;
    for (const std::string& t : runs[i].gone) gone += (gone.empty() ? "" : ", ") + t;
    md << "| " << runs[i].name << " | " << gone << " | " << w.frames << " of " << runs[i].run.frames.size() << " | "
       << ms(w.saved_ms) << " | " << ms(w.own_ms) << " | " << ms(w.saved_ms - w.own_ms) << " | "
       << ms(equal_work_tolerance(w, noise_equal)) << " | "
       << (w.frames == 0 ? "no frame of equal work" : equal_work_holds(w, noise_equal) ? "yes" : "**no**") << " |\n";
  }
  md << "\n## Effects the scene does not list cost nothing\n\n"
     << "| effect | term built | its time in the profile | its code run |\n|---|---|---|---|\n";
  for (Effect e : {Effect::gravity, Effect::inertia, Effect::damping, Effect::incompressibility, Effect::cavity}) {
    if (base.effects.has(e)) continue;
    const bool shared = (e == Effect::gravity && own_ms_per_frame(full.run, "loads") > 0) || e == Effect::incompressibility;
    const bool built = std::find(terms.begin(), terms.end(), term_of(e)) != terms.end();
    std::string term = built ? "yes" : "no", time = ms(own_ms_per_frame(full.run, term_of(e))) + " ms";
    if (e == Effect::incompressibility) term = "none of its own (mean dilatation, a mode of elasticity): off", time = "-";
    else if (shared) term = "`loads`, for the scene's tractions only", time = "-";
    md << "| " << config::to_string(e) << " | " << term << " | " << time << " | "
       << (e == Effect::gravity ? std::to_string(full.gravity_calls) + " gravity evaluations"
                                : built && e != Effect::incompressibility ? "yes" : "never") << " |\n";
  }
  md << "\nAn unlisted effect's term is never built (`fem/term.h`): the scene as is *is* the scene without it, so its frame "
        "time equals that scene's by construction, within the noise above.\n";
  bars.series = {term_bars, saved_bars, own_equal_bars, equal_bars};
  if (display_available()) {
    write_chart_png(bars, out / "effects.png");
    md << "\n![effects](effects.png)\n";
  } else {
    log::warning() << no_display_hint(out / "effects.png");
    md << "\nNot drawn: " << no_display_hint(out / "effects.png") << ".\n";
  }
  write_text_file(out / "report.md", md.str());

  std::ostringstream json_text;
  JsonWriter json(json_text);
  json.begin_object().key("scene").value(base.name).key("noise_ms").value(noise).key("noise_equal_work_ms").value(noise_equal);
  json.key("runs").begin_array();
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const EffectRun& r = runs[i];
    json.begin_object().key("run").value(r.name).key("frame_mean_ms").value(r.mean_ms).key("frame_p50_ms").value(r.p50_ms)
        .key("frame_p99_ms").value(r.p99_ms).key("newton_per_frame").value(r.newton).key("linear_per_frame").value(r.linear)
        .key("gravity_evaluations").value(r.gravity_calls);
    json.key("own_ms_per_frame").begin_object();
    for (const StudyTermTime& t : r.run.terms) json.key(t.name).value(own_ms_per_frame(r.run, t.name));
    json.end_object();
    if (i >= 2)
      json.key("equal_work").begin_object().key("frames").value(equal[i].frames).key("saved_ms").value(equal[i].saved_ms)
          .key("own_ms").value(equal[i].own_ms).key("tolerance_ms").value(equal_work_tolerance(equal[i], noise_equal))
          .key("holds").value(equal_work_holds(equal[i], noise_equal)).end_object();
    json.end_object();
  }
  json.end_array().end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), o.json)) {
    std::printf("%-34s %10s %10s %10s %12s\n", "run", "mean (ms)", "p50 (ms)", "p99 (ms)", "equal work");
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const EffectRun& r = runs[i];
      std::string verdict;
      if (i >= 2) verdict = equal[i].frames == 0 ? "no frames" : equal_work_holds(equal[i], noise_equal) ? "holds" : "DOES NOT HOLD";
      std::printf("%-34s %10.3f %10.3f %10.3f %12s\n", r.name.c_str(), r.mean_ms, r.p50_ms, r.p99_ms, verdict.c_str());
    }
    std::printf("noise (the scene twice): %.3f ms; wrote %s and %s\n", noise, (out / "table.csv").string().c_str(),
                (out / "report.md").string().c_str());
  }
  return kExitOk;
}

}  // namespace fetouch::app
