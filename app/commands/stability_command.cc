// `fetouch stability`: is a local model / hold / gain choice stable on a given tissue, and how does
// it feel? Poles and spectral radius of the lifted loop (haptics/stability_analysis.h), the closed-
// form cross-check where one exists, steady-state force and proxy offset, 2 % settling times.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/chart_png.h"
#include "app/cli.h"
#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/progress.h"
#include "haptics/stability_analysis.h"
#include "haptics/stability_region.h"
#include "haptics/step_response.h"

namespace fetouch::app {

namespace {

struct StabilityOptions {
  std::string local_model = "pi";
  std::string hold = "zoh";
  int ratio = 50;
  double k0 = 1.0, b0 = 0.0, kh = 0.5, ni = 0.0;
  double rate_hz = 1000;
  double duration_s = 10;
  bool json = false;
  std::string region, volume, step;      // output paths (stem; .csv and .png are written)
  std::vector<double> kh_range, ni_range, k0_values{0.5, 1.0, 2.0};
  int points = 101;
  std::vector<double> hand;  // --hand MASS STIFFNESS DAMPING (SI), or none
};

namespace fs = std::filesystem;

// "out/region", "out/region.csv" and "out/region.png" all name the pair out/region.{csv,png}.
fs::path stem_of(const std::string& path) {
  fs::path p(path);
  if (p.extension() == ".csv" || p.extension() == ".png") p.replace_extension();
  return p;
}

std::ofstream open_csv(const fs::path& path) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  out << std::setprecision(10);
  return out;
}

// Draws the chart unless there is no display; says what happened either way.
void draw(const Chart& chart, const fs::path& png) {
  if (!display_available()) {
    log::warning() << no_display_hint(png);
    return;
  }
  write_chart_png(chart, png);
  log::info() << "wrote " << png.string();
}

// The default axes: a coarse 41 x 41 scan of [0, 3 (K0 + B0)]^2 finds the stable set, and the
// axes cover it with two coarse cells to spare (the whole scan if nothing is stable).
haptics::RegionGrid fit_grid(const haptics::LoopParameters& base) {
  haptics::RegionGrid coarse;
  const double top = 3 * (base.stiffness(0, 0) + base.damping(0, 0));
  coarse.kh_max = coarse.ni_max = top;
  coarse.kh_points = coarse.ni_points = 41;
  const auto region = haptics::stability_region(base, coarse);
  double kh_low = top, kh_high = 0, ni_low = top, ni_high = 0;
  for (size_t a = 0; a < region.kh.size(); ++a)
    for (size_t b = 0; b < region.ni.size(); ++b)
      if (region.at(a, b) < 1) {
        kh_low = std::min(kh_low, region.kh[a]), kh_high = std::max(kh_high, region.kh[a]);
        ni_low = std::min(ni_low, region.ni[b]), ni_high = std::max(ni_high, region.ni[b]);
      }
  if (kh_high < kh_low) return coarse;
  const double cell = top / 40;
  haptics::RegionGrid fitted = coarse;
  fitted.kh_min = std::max(0.0, kh_low - 2 * cell);
  fitted.kh_max = std::min(top, kh_high + 2 * cell);
  fitted.ni_min = std::max(0.0, ni_low - 2 * cell);
  fitted.ni_max = std::min(top, ni_high + 2 * cell);
  return fitted;
}

void progress_callback(double fraction, void* context) {
  static_cast<Progress*>(context)->update(static_cast<long>(fraction * 1000));
}

haptics::StabilityRegion compute_region(const haptics::LoopParameters& base, const haptics::RegionGrid& grid,
                                        const std::string& label) {
  // Progress only where it is worth watching (a second or more).
  if (static_cast<long>(grid.kh_points) * grid.ni_points < 40000) return haptics::stability_region(base, grid);
  Progress progress(label, 1000, std::cerr, Progress::stderr_is_terminal());
  auto region = haptics::stability_region(base, grid, progress_callback, &progress);
  progress.finish();
  return region;
}

// The closed-form verdict (Jury on the characteristic polynomial) for P and PI, else -1.
int jury_verdict(haptics::LoopParameters p, double kh, double ni) {
  if (haptics::has_predictor(p.local_model)) return -1;
  p.gains = {kh, ni / p.ratio};
  return haptics::jury_stable(haptics::characteristic_polynomial(p)) ? 1 : 0;
}

// The outline of the stable set of a region: for each Kh with stable points, the lowest and the
// highest stable N*I, walked as one closed line (lower edge left to right, upper edge back).
ChartSeries outline(const haptics::StabilityRegion& r, const std::string& name, std::array<unsigned char, 3> color) {
  ChartSeries s{name, {}, {}, color, false, 2.5f};
  std::vector<std::pair<double, double>> upper;
  for (size_t a = 0; a < r.kh.size(); ++a) {
    int low = -1, high = -1;
    for (size_t b = 0; b < r.ni.size(); ++b)
      if (r.at(a, b) < 1) {
        if (low < 0) low = static_cast<int>(b);
        high = static_cast<int>(b);
      }
    if (low < 0) continue;
    s.x.push_back(r.kh[a]);
    s.y.push_back(r.ni[low]);
    upper.emplace_back(r.kh[a], r.ni[high]);
  }
  for (auto it = upper.rbegin(); it != upper.rend(); ++it) s.x.push_back(it->first), s.y.push_back(it->second);
  if (!s.x.empty()) s.x.push_back(s.x.front()), s.y.push_back(s.y.front());
  return s;
}

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string describe(const haptics::LoopParameters& p, const StabilityOptions& o) {
  std::ostringstream out;
  out << o.local_model << ", " << o.hold << ", N = " << p.ratio;
  return out.str();
}

void write_region(const StabilityOptions& o, const haptics::LoopParameters& base, const haptics::RegionGrid& grid) {
  const fs::path stem = stem_of(o.region);
  const auto region = compute_region(base, grid, "region");
  const bool integral = haptics::has_integrator(base.local_model);
  long agree = 0, compared = 0;
  {
    std::ofstream csv = open_csv(fs::path(stem).concat(".csv"));
    csv << "kh,ni,spectral_radius,stable,closed_form_stable\n";
    for (size_t a = 0; a < region.kh.size(); ++a)
      for (size_t b = 0; b < region.ni.size(); ++b) {
        const double r = region.at(a, b);
        const int jury = jury_verdict(base, region.kh[a], region.ni[b]);
        csv << region.kh[a] << ',' << region.ni[b] << ',' << r << ',' << (r < 1) << ',' << jury << '\n';
        if (jury >= 0 && std::abs(r - 1) > 1e-9) ++compared, agree += (jury == 1) == (r < 1);
      }
    if (!csv) throw std::runtime_error("cannot write " + stem.string() + ".csv");
  }
  std::cout << "region: " << region.stable_points() << " of " << region.radius.size()
            << " grid points stable; written to " << stem.string() << ".csv\n";
  if (compared) std::cout << "  closed form (Jury) agrees at " << agree << " of " << compared << " points\n";

  Chart chart;
  chart.title = "Stability region: " + describe(base, o) + ", K0 = " + number(o.k0) + ", B0 = " + number(o.b0);
  chart.x_label = "Kh";
  if (integral) {
    chart.y_label = "N*I";
    ChartSeries fast{"radius < 0.5", {}, {}, {0, 110, 50}, true, 6}, slow{"0.5 <= radius < 0.9", {}, {}, {90, 190, 90}, true, 6},
        edge{"0.9 <= radius < 1", {}, {}, {230, 190, 40}, true, 6};
    for (size_t a = 0; a < region.kh.size(); ++a)
      for (size_t b = 0; b < region.ni.size(); ++b) {
        const double r = region.at(a, b);
        ChartSeries* target = r < 0.5 ? &fast : r < 0.9 ? &slow : r < 1 ? &edge : nullptr;
        if (target) target->x.push_back(region.kh[a]), target->y.push_back(region.ni[b]);
      }
    chart.series = {fast, slow, edge};
    if (!haptics::has_predictor(base.local_model)) {
      // Jury's boundary, found independently on a finer N*I scan for each Kh.
      ChartSeries jury{"closed-form boundary (Jury)", {}, {}, {0, 0, 0}, true, 5};
      const int fine = 4 * static_cast<int>(region.ni.size());
      for (double kh : region.kh) {
        int previous = -1;
        for (int b = 0; b <= fine; ++b) {
          const double ni = grid.ni_min + (grid.ni_max - grid.ni_min) * b / fine;
          const int verdict = jury_verdict(base, kh, ni);
          if (previous >= 0 && verdict != previous) jury.x.push_back(kh), jury.y.push_back(ni);
          previous = verdict;
        }
      }
      chart.series.push_back(jury);
    }
  } else {
    chart.y_label = "spectral radius";
    ChartSeries radius{"spectral radius", region.kh, region.radius, {0, 90, 170}, false, 2.5f};
    ChartSeries one{"stability limit", {region.kh.front(), region.kh.back()}, {1, 1}, {200, 0, 0}, false, 1.5f};
    chart.series = {radius, one};
  }
  draw(chart, fs::path(stem).concat(".png"));
}

void write_volume(const StabilityOptions& o, const haptics::LoopParameters& base, const haptics::RegionGrid& grid) {
  if (!haptics::has_integrator(base.local_model))
    throw std::invalid_argument("--volume needs an integral axis: use --local-model pi or pi_smith");
  const fs::path stem = stem_of(o.volume);
  std::ofstream csv = open_csv(fs::path(stem).concat(".csv"));
  csv << "k0,kh,ni,spectral_radius,stable\n";
  Chart chart;
  chart.title = "Stability volume: " + describe(base, o) + ", B0 = " + number(o.b0) + " (outlines per K0)";
  chart.x_label = "Kh";
  chart.y_label = "N*I";
  const std::array<std::array<unsigned char, 3>, 6> colors{{{0, 90, 170}, {200, 60, 0}, {0, 140, 60}, {140, 0, 140}, {120, 120, 0}, {0, 0, 0}}};
  for (size_t v = 0; v < o.k0_values.size(); ++v) {
    haptics::LoopParameters p = base;
    p.stiffness(0, 0) = o.k0_values[v];
    std::ostringstream label;
    label << "K0 = " << o.k0_values[v];
    const auto region = compute_region(p, grid, label.str());
    for (size_t a = 0; a < region.kh.size(); ++a)
      for (size_t b = 0; b < region.ni.size(); ++b)
        csv << region.k0 << ',' << region.kh[a] << ',' << region.ni[b] << ',' << region.at(a, b) << ','
            << (region.at(a, b) < 1) << '\n';
    std::cout << label.str() << ": " << region.stable_points() << " of " << region.radius.size() << " grid points stable\n";
    chart.series.push_back(outline(region, label.str(), colors[v % colors.size()]));
  }
  if (!csv) throw std::runtime_error("cannot write " + stem.string() + ".csv");
  std::cout << "volume written to " << stem.string() << ".csv\n";
  draw(chart, fs::path(stem).concat(".png"));
}

void write_step(const StabilityOptions& o, const haptics::StepResponse& step) {
  const fs::path stem = stem_of(o.step);
  {
    std::ofstream csv = open_csv(fs::path(stem).concat(".csv"));
    csv << "t_s,device,proxy,surface,force\n";
    for (size_t k = 0; k < step.force.size(); ++k)
      csv << k * step.period_s << ",1," << step.proxy[k] << ',' << step.surface[k] << ',' << step.force[k] << '\n';
    if (!csv) throw std::runtime_error("cannot write " + stem.string() + ".csv");
  }
  std::cout << "step response written to " << stem.string() << ".csv\n";
  Chart chart;
  chart.title = "Step response: " + o.local_model + ", " + o.hold + ", K0 = " + number(o.k0) + ", Kh = " + number(o.kh);
  chart.x_label = "time (s)";
  chart.y_label = "position (device step = 1) and force";
  std::vector<double> t(step.force.size());
  for (size_t k = 0; k < t.size(); ++k) t[k] = k * step.period_s;
  chart.series = {{"device", t, std::vector<double>(t.size(), 1.0), {120, 120, 120}, false, 1.5f},
                  {"proxy (held surface)", t, step.proxy, {0, 140, 60}, false, 2.0f},
                  {"surface", t, step.surface, {0, 90, 170}, false, 2.0f},
                  {"force", t, step.force, {200, 40, 0}, false, 2.0f}};
  draw(chart, fs::path(stem).concat(".png"));
}

std::string complex_text(std::complex<double> z) {
  std::ostringstream out;
  out << std::setprecision(6) << z.real();
  if (std::abs(z.imag()) > 1e-12) out << (z.imag() < 0 ? " - " : " + ") << std::abs(z.imag()) << "j";
  return out.str();
}

int run_stability(const StabilityOptions& o) {
  using namespace haptics;
  LocalModelKind kind = LocalModelKind::pi_smith;
  parse_local_model(o.local_model, kind);  // one of the four: the option accepts nothing else
  const HoldKind hold = o.hold == "zoh" ? HoldKind::zoh : HoldKind::foh;
  const bool integral = has_integrator(kind);
  if (!integral && o.ni != 0) {
    std::cerr << "error: --ni is the integral gain N*I; local model " << o.local_model
              << " has none (use pi or pi_smith)\n";
    return kExitBadInput;
  }
  for (const auto& [option, range] : {std::pair<const char*, const std::vector<double>*>{"--kh-range", &o.kh_range}, {"--ni-range", &o.ni_range}})
    if (range->size() == 2 && !((*range)[0] < (*range)[1])) {
      std::cerr << "error: " << option << ": MIN " << (*range)[0] << " must be below MAX " << (*range)[1] << "\n";
      return kExitBadInput;
    }
  const auto p = LoopParameters::scalar(kind, hold, o.ratio, o.k0, o.b0, o.kh, o.ni / o.ratio);
  if (!o.region.empty() || !o.volume.empty()) {
    double k0_max = o.k0;
    if (!o.volume.empty()) k0_max = *std::max_element(o.k0_values.begin(), o.k0_values.end());
    auto base = p;
    base.stiffness(0, 0) = k0_max;
    const RegionGrid fitted = fit_grid(base);
    RegionGrid grid;
    grid.kh_min = o.kh_range.empty() ? fitted.kh_min : o.kh_range[0];
    grid.kh_max = o.kh_range.empty() ? fitted.kh_max : o.kh_range[1];
    grid.ni_min = o.ni_range.empty() ? fitted.ni_min : o.ni_range[0];
    grid.ni_max = o.ni_range.empty() ? fitted.ni_max : o.ni_range[1];
    grid.kh_points = grid.ni_points = o.points;
    try {
      if (!o.region.empty()) write_region(o, p, grid);
      if (!o.volume.empty()) write_volume(o, p, grid);
    } catch (const std::invalid_argument& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitFailure;
    }
    if (o.step.empty()) return kExitOk;
  }
  const StabilityResult result = analyse(p);
  // The loop with a hand holding the device (SI: K0 and Kh in N/m, T from --rate-hz).
  std::optional<StabilityResult> with_hand;
  if (o.hand.size() == 3) {
    auto held = p;
    HandParameters hand;
    hand.mass_kg = o.hand[0], hand.stiffness_n_per_m = o.hand[1], hand.damping_n_s_per_m = o.hand[2];
    if (!(hand.mass_kg > 0) || !(hand.stiffness_n_per_m > 0) || !(hand.damping_n_s_per_m >= 0)) {
      std::cerr << "error: --hand: the mass and stiffness must be positive and the damping not negative, not " << o.hand[0]
                << " " << o.hand[1] << " " << o.hand[2] << "\n";
      return kExitBadInput;
    }
    held.hand = hand;
    held.period_s = 1.0 / o.rate_hz;
    with_hand = analyse(held);
  }
  std::vector<std::complex<double>> poles;  // the dynamic ones; zeros are pure delays
  for (const auto& z : result.poles)
    if (std::abs(z) > 1e-4) poles.push_back(z);  // defective zeros come out at ~eps^(1/k)
  const double period = 1.0 / o.rate_hz;
  const StepResponse step = simulate_step(p, period, o.duration_s);
  const bool stable = result.stable();
  const bool stable_with_hand = !with_hand || with_hand->stable();
  if (!o.step.empty()) {
    try {
      write_step(o, step);
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
      return kExitFailure;
    }
  }

  if (o.json) {
    JsonWriter json(std::cout);
    json.begin_object();
    json.key("local_model").value(o.local_model);
    json.key("hold").value(o.hold);
    json.key("ratio").value(o.ratio);
    json.key("k0").value(o.k0);
    json.key("b0").value(o.b0);
    json.key("kh").value(o.kh);
    json.key("ni").value(o.ni);
    json.key("spectral_radius").value(result.spectral_radius);
    json.key("stable").value(stable);
    if (with_hand) {
      json.key("hand").begin_array().value(o.hand[0]).value(o.hand[1]).value(o.hand[2]).end_array();
      json.key("spectral_radius_with_hand").value(with_hand->spectral_radius);
      json.key("stable_with_hand").value(with_hand->stable());
    }
    json.key("poles").begin_array();
    for (const auto& z : poles) json.begin_array().value(z.real()).value(z.imag()).end_array();
    json.end_array();
    json.key("steady_force").value(step.steady_force);
    json.key("steady_proxy_offset").value(1.0 - step.steady_surface);
    json.key("force_settling_s");
    stable && step.force_settling_s >= 0 ? json.value(step.force_settling_s) : json.null();
    json.key("surface_settling_s");
    stable && step.surface_settling_s >= 0 ? json.value(step.surface_settling_s) : json.null();
    json.end_object();
  } else {
    std::cout << "local model " << o.local_model << ", hold " << o.hold << ", N = " << o.ratio
              << ", K0 = " << o.k0 << ", B0 = " << o.b0 << ", Kh = " << o.kh;
    if (integral) std::cout << ", N*I = " << o.ni;
    std::cout << "\n  spectral radius  " << std::setprecision(6) << result.spectral_radius
              << (stable ? "  (stable)" : "  (UNSTABLE)") << "\n  poles            ";
    for (size_t i = 0; i < poles.size(); ++i) std::cout << (i ? ", " : "") << complex_text(poles[i]);
    if (poles.empty()) std::cout << "all at 0 (deadbeat)";
    std::cout << "\n  steady state     force " << step.steady_force << " x_h, proxy offset "
              << 1.0 - step.steady_surface << " x_h";
    const auto settle = [&](double t) {
      return !stable ? std::string("never (unstable)")
                     : t < 0 ? "more than " + std::to_string(o.duration_s) + " s"
                             : std::to_string(t) + " s";
    };
    std::cout << "\n  2 % settling     force " << settle(step.force_settling_s) << ", surface "
              << settle(step.surface_settling_s) << "\n";
    if (with_hand)
      std::cout << "  with the hand    " << o.hand[0] << " kg, " << o.hand[1] << " N/m, " << o.hand[2]
                << " N s/m: spectral radius " << with_hand->spectral_radius
                << (with_hand->stable() ? "  (stable)" : "  (UNSTABLE: the loop with this hand in it rings)") << "\n";
  }
  return stable && stable_with_hand ? kExitOk : kExitFailure;
}

}  // namespace

void add_stability_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<StabilityOptions>();
  CLI::App* cmd = parent.add_subcommand("stability", drawing_command_description("stability"));
  cmd->footer(
      "One contact, normalised units as in the seed: K0 the tissue's stiffness, B0 its damping in the\n"
      "frame-rate law (K0 + B0(1 - z^-1)) x_o = F, Kh and N*I the local model's gains. Prints the\n"
      "poles of the lifted one-frame loop, its spectral radius, the steady-state force and proxy\n"
      "offset for a unit device step, and 2 % settling times from a lockstep simulation.\n"
      "Exit code 0 if stable, 1 if not.\n"
      "Files: --region STEM writes STEM.csv (kh, ni, spectral radius, verdict, closed-form verdict)\n"
      "and STEM.png, the region over (Kh, N*I); --volume STEM the same over several K0 (--k0-values);\n"
      "--step STEM the step response (time, device, proxy, surface, force). The PNGs need an X\n"
      "display: run under xvfb-run -a on a headless machine. With --region or --volume alone the\n"
      "exit code says whether the files were written.\n"
      "Examples: fetouch stability --local-model p --k0 0.2 --kh 0.19   (rings: pole -0.95)\n"
      "          xvfb-run -a fetouch stability --local-model pi --hold foh --region out/pi_foh\n"
      "          fetouch stability --local-model pi --hold foh --k0 23840 --kh 5235 --ni 7915 --hand 0.3 300 8\n"
      "            (the 1 MPa block's gains proven without the hand: stable, and UNSTABLE with it)");
  cmd->add_option("--local-model", o->local_model, "p, pi, smith or pi_smith")
      ->check(CLI::IsMember({"p", "pi", "smith", "pi_smith"}))
      ->capture_default_str();
  cmd->add_option("--hold", o->hold, "zoh or foh")->check(CLI::IsMember({"zoh", "foh"}))->capture_default_str();
  cmd->add_option("-N,--ratio", o->ratio, "Haptic ticks per solver frame")
      ->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--k0", o->k0, "Tissue stiffness K0 (> 0)")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--b0", o->b0, "Tissue damping B0 (>= 0)")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_option("--kh", o->kh, "Proportional gain Kh")->capture_default_str();
  cmd->add_option("--ni", o->ni, "Integral gain N*I (pi and pi_smith)")->capture_default_str();
  cmd->add_option("--rate-hz", o->rate_hz, "Haptic rate, for times in seconds")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--duration", o->duration_s, "Simulated time of the step response, s")
      ->check(CLI::Range(1e-6, 3600.0))->capture_default_str();
  cmd->add_flag("--json", o->json, "Print a JSON report");
  cmd->add_option("--hand", o->hand,
                  "Also analyse the loop with a one-mass hand holding the device: MASS (kg) STIFFNESS (N/m) DAMPING "
                  "(N s/m); K0 and Kh are then in N/m and T is 1 / --rate-hz")
      ->expected(3);
  cmd->add_option("--region", o->region, "Write the stability region over (Kh, N*I) to STEM.csv and STEM.png");
  cmd->add_option("--volume", o->volume, "Write the stability volume over K0 to STEM.csv and STEM.png");
  cmd->add_option("--step", o->step, "Write the step response to STEM.csv and STEM.png");
  cmd->add_option("--kh-range", o->kh_range, "Kh axis of --region/--volume: MIN MAX (default 0 .. 2.5 (K0 + B0))")
      ->expected(2);
  cmd->add_option("--ni-range", o->ni_range, "N*I axis of --region/--volume: MIN MAX (default as Kh)")->expected(2);
  cmd->add_option("--points", o->points, "Grid points per axis of --region/--volume")
      ->check(CLI::Range(2, 2001))->capture_default_str();
  cmd->add_option("--k0-values", o->k0_values, "K0 values of --volume")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->callback([o, &exit_code]() { exit_code = run_stability(*o); });
}

}  // namespace fetouch::app
