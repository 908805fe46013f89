// What `fetouch study accuracy` writes: STUDY/table.csv, STUDY/report.md and the plots.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "app/chart_png.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/output_guard.h"
#include "app/study/study.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

std::string percent(double x) {
  if (std::isnan(x)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, x < 1e-4 ? "%.2g %%" : "%.3g %%", 100 * x);
  return text;
}
std::string fixed(double x, int digits) {
  if (std::isnan(x)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, x);
  return text;
}

// The rows of an axis with the baseline, in the order the knob goes from cheap to dear.
std::vector<std::size_t> axis_rows(const StudyTable& t, const std::string& axis) {
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.rows[i][0] == axis || t.rows[i][0] == "baseline") rows.push_back(i);
  const auto key = [&t, &axis](std::size_t i) {
    if (axis == "mesh" || axis == "order") return t.number(i, "dofs");
    if (axis == "tolerance") {
      const double tol = t.number(i, "newton_tolerance");
      return std::isnan(tol) ? 0.0 : -tol;  // the scene's own policy: after the loosest
    }
    if (axis == "rate") return -t.number(i, "ratio");
    return t.number(i, "frame_p99_ms");
  };
  std::stable_sort(rows.begin(), rows.end(), [&key](std::size_t a, std::size_t b) { return key(a) < key(b); });
  return rows;
}

std::string knob(const StudyTable& t, std::size_t i, const std::string& axis) {
  const auto& r = t.rows[i];
  if (axis == "mesh") return "level " + r[1] + " (" + r[3] + " DOFs)";
  if (axis == "order") return "P" + r[4] + " (" + r[3] + " DOFs)";
  if (axis == "tolerance") return r[5].empty() ? "the scene's accuracy policy" : "tolerance " + r[5];
  if (axis == "rate") return "N = " + r[6];
  return r[7] + "/" + r[8];
}

std::string axis_sentence(const StudyTable& t, const std::string& axis, const PowerFit& fit) {
  const std::vector<std::size_t> rows = axis_rows(t, axis);
  if (rows.size() < 2) return "";
  const std::map<std::string, std::string> names = {{"mesh", "Element size"}, {"order", "Element order"},
                                                    {"tolerance", "Newton tolerance"}, {"rate", "Solver rate"},
                                                    {"model", "Local model and hold"}};
  std::ostringstream s;
  s << "- **" << names.at(axis) << ":** ";
  if (axis == "model") {
    std::size_t best = rows.front(), worst = rows.front();
    for (std::size_t i : rows) {
      if (t.number(i, "force_rms_rel") < t.number(best, "force_rms_rel")) best = i;
      if (t.number(i, "force_rms_rel") > t.number(worst, "force_rms_rel")) worst = i;
    }
    s << "the model costs the solver nothing (it runs in the haptic loop); the force error ranges from "
      << percent(t.number(best, "force_rms_rel")) << " (" << knob(t, best, axis) << ") to "
      << percent(t.number(worst, "force_rms_rel")) << " (" << knob(t, worst, axis) << "); against their own discretisation's ideal, from "
      << percent(t.number(best, "force_rms_rel_own_ideal")) << " to " << percent(t.number(worst, "force_rms_rel_own_ideal")) << ".";
    return s.str();
  }
  const std::size_t a = rows.front(), b = rows.back();
  s << "from " << knob(t, a, axis) << " to " << knob(t, b, axis) << " the force error goes from "
    << percent(t.number(a, "force_rms_rel")) << " to " << percent(t.number(b, "force_rms_rel"))
    << " and the felt stiffness error from " << percent(t.number(a, "felt_stiffness_rel")) << " to "
    << percent(t.number(b, "felt_stiffness_rel")) << ", while the frame p99 goes from "
    << fixed(t.number(a, "frame_p99_ms"), 2) << " to " << fixed(t.number(b, "frame_p99_ms"), 2) << " ms";
  if (axis == "rate") s << " (a frame's budget from " << t.rows[a][12] << " to " << t.rows[b][12] << " ms)";
  if (axis == "rate" || axis == "tolerance")
    s << "; against their own discretisation's ideal the error goes from " << percent(t.number(a, "force_rms_rel_own_ideal"))
      << " to " << percent(t.number(b, "force_rms_rel_own_ideal"));
  if (axis == "mesh" && !std::isnan(fit.slope))
    s << "; the discretisation's own error falls as DOFs^" << fixed(fit.slope, 2) << ", order " << fixed(-3 * fit.slope, 2)
      << " in the element size";
  s << ".";
  return s.str();
}

}  // namespace

void prepare_study_folder(const fs::path& out, const std::string& scene_file, const config::Scene& scene) {
  std::vector<NamedInput> inputs = {{scene_file, "the scene"}, {scene.mesh.path, "the scene's mesh"}};
  for (const config::Probe& probe : scene.probes) inputs.emplace_back(probe.device.trajectory, "the trajectory of probe " + probe.name);
  const auto writes = [](const std::string& file) {
    return file == "table.csv" || file == "report.md" || file == "study.json" || fs::path(file).extension() == ".png";
  };
  refuse_overwriting({out}, inputs, out, writes);
  fs::create_directories(out);
}

PowerFit convergence_fit(const StudyTable& t) {
  std::vector<double> dofs, error;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.rows[i][0] == "mesh" || t.rows[i][0] == "baseline") {
      if (t.rows[i][0] == "baseline" && t.rows[i][1] != "0") continue;
      dofs.push_back(t.number(i, "dofs"));
      error.push_back(t.number(i, "discretisation_rel"));
    }
  return fit_power_law(dofs, error);
}

int write_accuracy_outputs(const AccuracyOptions& o, const config::Scene& scene, const StudyTable& t,
                           const AccuracyReference& ref) {
  const fs::path out(o.out);
  write_csv(t, out / "table.csv");
  const PowerFit fit = convergence_fit(t);
  // The plots: error against frame time (the Pareto front drawn through its rows), error against DOFs.
  std::vector<std::string> plots;
  Chart trade;
  trade.title = "Force error against frame time (" + scene.name + ")";
  trade.x_label = "frame time p99 (ms)", trade.y_label = "force error (RMS, relative)";
  trade.log_x = trade.log_y = true;
  ChartSeries all{"configurations", {}, {}, {90, 90, 90}, true, 7};
  ChartSeries front{"Pareto front", {}, {}, {220, 30, 30}, false, 2.5f};
  std::vector<std::pair<double, double>> front_points;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const double x = t.number(i, "frame_p99_ms"), y = t.number(i, "force_rms_rel");
    if (!(x > 0) || !(y > 0)) continue;
    all.x.push_back(x), all.y.push_back(y);
    if (t.rows[i].back() == "1") front_points.emplace_back(x, y);
  }
  std::sort(front_points.begin(), front_points.end());
  for (const auto& [x, y] : front_points) front.x.push_back(x), front.y.push_back(y);
  trade.series = {all, front};
  Chart convergence;
  convergence.title = "Force error against DOFs under refinement (" + scene.name + ")";
  convergence.x_label = "DOFs", convergence.y_label = "discretisation's force error (RMS, relative)";
  convergence.log_x = convergence.log_y = true;
  ChartSeries mesh{"mesh levels (their ideal against the reference)", {}, {}, {30, 90, 200}, true, 8};
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if ((t.rows[i][0] == "mesh" || t.rows[i][0] == "baseline") && t.number(i, "discretisation_rel") > 0)
      mesh.x.push_back(t.number(i, "dofs")), mesh.y.push_back(t.number(i, "discretisation_rel"));
  convergence.series.push_back(mesh);
  if (!std::isnan(fit.slope) && !mesh.x.empty()) {
    const auto [lo, hi] = std::minmax_element(mesh.x.begin(), mesh.x.end());
    ChartSeries line{"fit: error ~ DOFs^" + fixed(fit.slope, 2), {*lo, *hi},
                     {fit.coefficient * std::pow(*lo, fit.slope), fit.coefficient * std::pow(*hi, fit.slope)}, {220, 30, 30}, false, 2};
    convergence.series.push_back(line);
  }
  std::string plot_note;
  for (const auto& [chart, name] : {std::pair<const Chart*, const char*>{&trade, "error_vs_frame_time.png"},
                                    {&convergence, "error_vs_dofs.png"}}) {
    if (!display_available()) {
      plot_note = no_display_hint(out / name);
      log::warning() << plot_note;
      continue;
    }
    write_chart_png(*chart, out / name);
    plots.push_back(name);
  }

  std::ostringstream md;
  md << "# Accuracy study: " << scene.name << "\n\n"
     << "Scene `" << o.scene << "`; " << (o.duration_s > 0 ? "the trajectory's first " + fixed(o.duration_s, 2) + " s" : "the whole trajectory")
     << "; lockstep replays on " << std::thread::hardware_concurrency() << " hardware threads, " << o.threads
     << " assembly thread(s). One knob turned at a time from the scene as it is (the `baseline` row).\n\n"
     << "## Reference\n\n" << ref.text << ", Newton to 1e-10 with the accuracy policy off: " << ref.dofs << " DOFs, "
     << ref.cells << " cells, " << ref.frames << " frames (frame p99 " << fixed(ref.frame_p99_ms, 2) << " ms), "
     << fixed(ref.wall_s, 1) << " s. Every row's force is compared with it tick by tick: the RMS of the difference "
     << "relative to the reference force's RMS, its peak (N), and the felt stiffness n'(W_pp)^-1 n at the reference's "
     << "peak force. The column *against own ideal* compares the row with its own discretisation's ideal (the same "
     << "mesh and order, N = 1, Newton to 1e-10): the error its solver rate, tolerance and local model add; "
     << "*within budget*: its frame p99 fits its frame's period (N ms at 1 kHz).\n\n"
     << (std::isnan(ref.self_check)
             ? std::string("Self-consistency: not run (--quick: it costs as much as the reference).")
             : "Self-consistency: the reference run again differs from itself by " + format_number(ref.self_check) +
                   " (RMS, relative; must be below 1e-6): " + (ref.self_check < 1e-6 ? "**holds**." : "**FAILS**."))
     << "\n\n"
     << "## Table\n\nPareto-optimal rows (no other row has both a smaller frame p99 and a smaller force error) are marked "
     << "**yes**; the same rows as `pareto` = 1 in `table.csv`.\n\n"
     << "| axis | mesh | DOFs | order | Newton tol | N | model/hold | frame p50 / p99 / max (ms) | Newton / frame | "
        "linear / frame | force RMS | peak (N) | felt stiffness | against own ideal | discretisation | within budget | Pareto |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    md << "| " << r[0] << " | " << r[1] << " | " << r[3] << " | P" << r[4] << " | " << (r[5].empty() ? "scene" : r[5]) << " | "
       << r[6] << " | " << r[7] << "/" << r[8] << " | " << fixed(t.number(i, "frame_p50_ms"), 2) << " / "
       << fixed(t.number(i, "frame_p99_ms"), 2) << " / " << fixed(t.number(i, "frame_max_ms"), 2) << " | "
       << fixed(t.number(i, "newton_per_frame"), 2) << " | " << fixed(t.number(i, "linear_per_frame"), 1) << " | "
       << percent(t.number(i, "force_rms_rel")) << " | " << fixed(t.number(i, "force_peak_n"), 4) << " | "
       << percent(t.number(i, "felt_stiffness_rel")) << " | " << percent(t.number(i, "force_rms_rel_own_ideal")) << " | "
       << percent(t.number(i, "discretisation_rel")) << " | " << (t.text(i, "within_budget") == "1" ? "yes" : "no") << " | "
       << (r.back() == "1" ? "**yes**" : "") << " |\n";
  }
  if (!ref.not_run.empty()) {
    md << "\nNot run:\n\n";
    for (const std::string& why : ref.not_run) md << "- " << why << "\n";
  }
  md << "\n## Convergence under refinement\n\nThe discretisation's own error: each mesh level's ideal (N = 1, Newton to 1e-10, the "
        "scene's order) against the reference (column `discretisation_rel`; the reference's own level has none).\n\n";
  if (std::isnan(fit.slope))
    md << "Not fitted: fewer than two mesh levels coarser than the reference's"
       << (scene.mesh.source == config::MeshSource::file ? " (a mesh read from a file has one level only)" : "") << ".\n";
  else
    md << "Least squares over the " << fit.points << " mesh levels: force error = " << format_number(fit.coefficient)
       << " DOFs^" << fixed(fit.slope, 3) << ", that is order **" << fixed(-3 * fit.slope, 2)
       << "** in the element size h (DOFs ~ h^-3).\n";
  md << "\n## What each axis buys\n\n";
  for (const char* axis : {"mesh", "order", "tolerance", "rate", "model"}) {
    const std::string s = axis_sentence(t, axis, fit);
    if (!s.empty()) md << s << "\n";
  }
  // The answer a user wants first: the cheapest configuration whose force is within 5 % of the
  // reference and whose frames fit their period.
  std::size_t best = t.rows.size();
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.text(i, "within_budget") == "1" && t.number(i, "force_rms_rel") <= 0.05 &&
        (best == t.rows.size() || t.number(i, "frame_p99_ms") < t.number(best, "frame_p99_ms")))
      best = i;
  if (best < t.rows.size()) {
    const auto& r = t.rows[best];
    md << "- **Cheapest within 5 % of the reference and within its frame's budget:** the " << r[0] << " row: level " << r[1]
       << ", P" << r[4] << ", " << (r[5].empty() ? std::string("the scene's tolerance") : "tolerance " + r[5]) << ", N = " << r[6]
       << ", " << r[7] << "/" << r[8] << " (" << r[3] << " DOFs): force error " << percent(t.number(best, "force_rms_rel"))
       << ", frame p99 " << fixed(t.number(best, "frame_p99_ms"), 2) << " ms of " << r[12] << ".\n";
  } else {
    md << "- **No configuration** is both within 5 % of the reference and within its frame's budget.\n";
  }
  md << "\n## Plots\n\n";
  for (const std::string& p : plots) md << "![" << p << "](" << p << ")\n\n";
  if (!plot_note.empty()) md << "Not drawn: " << plot_note << ".\n";
  write_text_file(out / "report.md", md.str());

  std::ostringstream json_text;
  JsonWriter json(json_text);
  json.begin_object();
  json.key("scene").value(scene.name);
  json.key("reference").begin_object().key("configuration").value(ref.text).key("dofs").value(static_cast<long>(ref.dofs))
      .key("frames").value(ref.frames);
  if (!std::isnan(ref.self_check)) json.key("self_check_rms_rel").value(ref.self_check);
  json.end_object();
  json.key("convergence").begin_object().key("points").value(static_cast<long>(fit.points));
  if (!std::isnan(fit.slope)) json.key("dofs_exponent").value(fit.slope).key("order_in_h").value(-3 * fit.slope);
  json.end_object();
  json.key("rows").begin_array();
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    json.begin_object();
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      const double x = t.number(i, t.columns[c]);
      if (!std::isnan(x)) json.key(t.columns[c]).value(x);
      else json.key(t.columns[c]).value(t.rows[i][c]);
    }
    json.end_object();
  }
  json.end_array();
  json.key("files").begin_array().value((out / "table.csv").string()).value((out / "report.md").string());
  for (const std::string& p : plots) json.value((out / p).string());
  json.end_array();
  json.end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), o.json)) {
    std::printf("reference: %s, %u DOFs; self-check %s\n", ref.text.c_str(), ref.dofs,
                std::isnan(ref.self_check) ? "not run (--quick)" : (format_number(ref.self_check) + " (must be < 1e-6)").c_str());
    std::printf("  %-9s %5s %7s %5s %9s %4s %-13s %9s %10s %8s\n", "axis", "mesh", "DOFs", "order", "tol", "N",
                "model/hold", "p99 (ms)", "force err", "Pareto");
    for (std::size_t i = 0; i < t.rows.size(); ++i) {
      const auto& r = t.rows[i];
      std::printf("  %-9s %5s %7s %5s %9s %4s %-13s %9.2f %10s %8s\n", r[0].c_str(), r[1].c_str(), r[3].c_str(),
                  ("P" + r[4]).c_str(), r[5].empty() ? "scene" : r[5].c_str(), r[6].c_str(), (r[7] + "/" + r[8]).c_str(),
                  t.number(i, "frame_p99_ms"), percent(t.number(i, "force_rms_rel")).c_str(), r.back() == "1" ? "yes" : "");
    }
    if (!std::isnan(fit.slope))
      std::printf("force error under refinement: DOFs^%.3f, order %.2f in h (%d levels)\n", fit.slope, -3 * fit.slope, fit.points);
    std::printf("wrote %s, %s%s\n", (out / "table.csv").string().c_str(), (out / "report.md").string().c_str(),
                plots.empty() ? "" : " and the plots");
  }
  return std::isnan(ref.self_check) || ref.self_check < 1e-6 ? kExitOk : kExitFailure;
}

}  // namespace fetouch::app
