// `fetouch study effects`: what each effect of a scene costs. The scene's session as it is (twice:
// the second run measures the noise), then with each listed effect removed in turn; each run's frame
// times and each term's assembly time per frame. An effect the scene does not list has no term: the
// profile shows none, and gravity's own counter (fem::gravity_evaluations) shows its code never ran.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <sstream>

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
  std::string name;  // "as is", "as is (again)", "without gravity", ...
  StudyRun run;
  long gravity_calls = 0;
  double mean_ms = 0, p50_ms = 0, p99_ms = 0, newton = 0;
};

double term_ms_per_frame(const StudyRun& r, const std::string& term) {
  for (const auto& [name, seconds] : r.term_assembly_s)
    if (name == term) return 1e3 * seconds / std::max<double>(1, static_cast<double>(r.frames.size()));
  return 0;
}

std::string ms(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f", x);
  return text;
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
  base.mesh = mesh_scene_volume(base.mesh);
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
  std::vector<EffectRun> runs;
  Progress progress("study effects", static_cast<long>(removals.size()) + 2, std::cerr, Progress::stderr_is_terminal());
  const auto measure = [&](const std::string& name, const config::Scene& scene) {
    log::info() << "study effects: " << name;
    EffectRun r;
    r.name = name;
    const long before = fem::gravity_evaluations();
    r.run = run_study_session(scene, loop_settings(scene), settings);
    r.gravity_calls = fem::gravity_evaluations() - before;
    std::vector<double> times;
    for (const StudyFrame& f : r.run.frames) times.push_back(1e3 * f.solve_s), r.newton += f.newton_iterations;
    const double frames = std::max<double>(1, static_cast<double>(times.size()));
    r.mean_ms = std::accumulate(times.begin(), times.end(), 0.0) / frames;
    r.p50_ms = percentile(times, 0.5), r.p99_ms = percentile(times, 0.99), r.newton /= frames;
    runs.push_back(std::move(r));
    progress.update(static_cast<long>(runs.size()));
  };
  measure("as is", base);
  measure("as is (again)", base);
  for (const auto& [name, gone] : removals) {
    config::Scene scene = base;
    auto& listed = scene.effects.listed;
    for (Effect e : gone) listed.erase(std::remove(listed.begin(), listed.end(), e), listed.end());
    measure(name, scene);
  }
  progress.finish();

  // The runs, and every term any of them built, per frame.
  std::vector<std::string> terms;
  for (const EffectRun& r : runs)
    for (const auto& [name, seconds] : r.run.term_assembly_s)
      if (std::find(terms.begin(), terms.end(), name) == terms.end()) terms.push_back(name);
  StudyTable table;
  table.columns = {"run", "frame_mean_ms", "frame_p50_ms", "frame_p99_ms", "newton_per_frame", "gravity_evaluations"};
  for (const std::string& t : terms) table.columns.push_back("assembly_ms_" + t);
  for (const EffectRun& r : runs) {
    std::vector<std::string> row = {r.name, format_number(r.mean_ms), format_number(r.p50_ms), format_number(r.p99_ms),
                                    format_number(r.newton), std::to_string(r.gravity_calls)};
    for (const std::string& t : terms) row.push_back(format_number(term_ms_per_frame(r.run, t)));
    table.rows.push_back(std::move(row));
  }
  write_csv(table, out / "table.csv");
  const EffectRun& full = runs[0];
  const double noise = std::abs(runs[0].mean_ms - runs[1].mean_ms);

  std::ostringstream md;
  md << "# Effects study: " << base.name << "\n\nScene `" << o.scene << "`; "
     << (duration > 0 ? "the trajectory's first " + ms(duration) + " s" : "the whole trajectory") << ", lockstep, "
     << full.run.frames.size() << " frames a run, " << full.run.dofs << " DOFs, " << o.threads << " assembly thread(s).\n\n"
     << "## Runs\n\n| run | frame mean (ms) | p50 | p99 | Newton / frame |";
  for (const std::string& t : terms) md << " " << t << " (ms / frame) |";
  md << "\n|---|---|---|---|---|";
  for (std::size_t i = 0; i < terms.size(); ++i) md << "---|";
  md << "\n";
  for (const EffectRun& r : runs) {
    md << "| " << r.name << " | " << ms(r.mean_ms) << " | " << ms(r.p50_ms) << " | " << ms(r.p99_ms) << " | " << ms(r.newton) << " |";
    for (const std::string& t : terms) md << " " << ms(term_ms_per_frame(r.run, t)) << " |";
    md << "\n";
  }
  md << "\nNoise: the same scene twice differs by " << ms(noise) << " ms in its mean frame time.\n\n"
     << "## What each listed effect costs\n\n| effect | its term | term's assembly (ms / frame) | share of the frame | "
        "frame time saved by removing it (ms) | share saved |\n|---|---|---|---|---|---|\n";
  Chart bars;
  bars.title = "What each effect costs a frame (" + base.name + ")";
  bars.x_label = "effect", bars.y_label = "ms per frame";
  ChartSeries term_bars{"its term's assembly", {}, {}, {40, 100, 200}, false, 2, true};
  ChartSeries saved_bars{"frame time saved without it", {}, {}, {220, 110, 30}, false, 2, true};
  for (Effect e : base.effects.listed) {
    const std::string name = config::to_string(e);
    const double term_ms = term_ms_per_frame(full.run, term_of(e));
    std::string saved = "-", saved_share = "not removable";
    double saved_ms = 0;
    for (std::size_t i = 0; i < removals.size(); ++i)
      if (removals[i].second.front() == e) {
        saved_ms = full.mean_ms - runs[i + 2].mean_ms;
        saved = ms(saved_ms), saved_share = ms(100 * saved_ms / full.mean_ms) + " %";
      }
    if (e == Effect::elasticity) saved_share = "always simulated";
    if (e == Effect::contact) saved_share = "the probes touch through it";
    md << "| " << name << " | " << term_of(e) << " | " << ms(term_ms) << " | " << ms(100 * term_ms / full.mean_ms) << " % | "
       << saved << " | " << saved_share << " |\n";
    bars.x_ticks.push_back(name);
    const double x = static_cast<double>(bars.x_ticks.size() - 1);
    term_bars.x.push_back(x), term_bars.y.push_back(term_ms);
    saved_bars.x.push_back(x), saved_bars.y.push_back(std::max(0.0, saved_ms));
  }
  md << "\nRemoving an effect also changes the Newton iterations a frame takes (a load that is no longer there, "
        "a time step that no longer damps), so the time saved can differ from the term's own share; both are "
        "measured, with the noise above.\n\n## Effects the scene does not list cost nothing\n\n"
     << "| effect | term built | its time in the profile | its code run |\n|---|---|---|---|\n";
  for (Effect e : {Effect::gravity, Effect::inertia, Effect::damping, Effect::incompressibility, Effect::cavity}) {
    if (base.effects.has(e)) continue;
    const bool shared = (e == Effect::gravity && term_ms_per_frame(full.run, "loads") > 0) || e == Effect::incompressibility;
    const bool built = std::find(terms.begin(), terms.end(), term_of(e)) != terms.end();
    std::string term = built ? "yes" : "no", time = ms(term_ms_per_frame(full.run, term_of(e))) + " ms";
    if (e == Effect::incompressibility) term = "none of its own (mean dilatation, a mode of elasticity): off", time = "-";
    else if (shared) term = "`loads`, for the scene's tractions only", time = "-";
    md << "| " << config::to_string(e) << " | " << term << " | " << time << " | "
       << (e == Effect::gravity ? std::to_string(full.gravity_calls) + " gravity evaluations"
                                : built && e != Effect::incompressibility ? "yes" : "never") << " |\n";
  }
  md << "\nAn unlisted effect's term is never built (`fem/term.h`): the scene as is *is* the scene without it, so its frame "
        "time equals that scene's by construction, within the noise above.\n";
  bars.series = {term_bars, saved_bars};
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
  json.begin_object().key("scene").value(base.name).key("noise_ms").value(noise).key("runs").begin_array();
  for (const EffectRun& r : runs) {
    json.begin_object().key("run").value(r.name).key("frame_mean_ms").value(r.mean_ms).key("frame_p50_ms").value(r.p50_ms)
        .key("frame_p99_ms").value(r.p99_ms).key("newton_per_frame").value(r.newton).key("gravity_evaluations").value(r.gravity_calls);
    json.key("assembly_ms_per_frame").begin_object();
    for (const auto& [name, seconds] : r.run.term_assembly_s) json.key(name).value(term_ms_per_frame(r.run, name));
    json.end_object().end_object();
  }
  json.end_array().end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), o.json)) {
    std::printf("%-34s %10s %10s %10s\n", "run", "mean (ms)", "p50 (ms)", "p99 (ms)");
    for (const EffectRun& r : runs) std::printf("%-34s %10.3f %10.3f %10.3f\n", r.name.c_str(), r.mean_ms, r.p50_ms, r.p99_ms);
    std::printf("noise (the scene twice): %.3f ms; wrote %s and %s\n", noise, (out / "table.csv").string().c_str(),
                (out / "report.md").string().c_str());
  }
  return kExitOk;
}

}  // namespace fetouch::app
