// `fetouch stability`: is a local model / hold / gain choice stable on a given tissue, and how does
// it feel? Poles and spectral radius of the lifted loop (haptics/stability_analysis.h), the closed-
// form cross-check where one exists, steady-state force and proxy offset, 2 % settling times.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "haptics/stability_analysis.h"
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
};

std::string complex_text(std::complex<double> z) {
  std::ostringstream out;
  out << std::setprecision(6) << z.real();
  if (std::abs(z.imag()) > 1e-12) out << (z.imag() < 0 ? " - " : " + ") << std::abs(z.imag()) << "j";
  return out.str();
}

int run_stability(const StabilityOptions& o) {
  using namespace haptics;
  const LocalModelKind kind = o.local_model == "p"       ? LocalModelKind::p
                              : o.local_model == "pi"    ? LocalModelKind::pi
                              : o.local_model == "smith" ? LocalModelKind::smith
                                                         : LocalModelKind::pi_smith;
  const HoldKind hold = o.hold == "zoh" ? HoldKind::zoh : HoldKind::foh;
  const bool integral = has_integrator(kind);
  if (!integral && o.ni != 0) {
    std::cerr << "error: --ni is the integral gain N*I; local model " << o.local_model
              << " has none (use pi or pi_smith)\n";
    return kExitBadInput;
  }
  const auto p = LoopParameters::scalar(kind, hold, o.ratio, o.k0, o.b0, o.kh, o.ni / o.ratio);
  const StabilityResult result = analyse(p);
  std::vector<std::complex<double>> poles;  // the dynamic ones; zeros are pure delays
  for (const auto& z : result.poles)
    if (std::abs(z) > 1e-4) poles.push_back(z);  // defective zeros come out at ~eps^(1/k)
  const double period = 1.0 / o.rate_hz;
  const StepResponse step = simulate_step(p, period, o.duration_s);
  const bool stable = result.stable();

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
  }
  return stable ? kExitOk : kExitFailure;
}

}  // namespace

void add_stability_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<StabilityOptions>();
  CLI::App* cmd = parent.add_subcommand("stability", "Analyse the stability of a local model on a tissue");
  cmd->footer(
      "One contact, normalised units as in the seed: K0 the tissue's stiffness, B0 its damping in the\n"
      "frame-rate law (K0 + B0(1 - z^-1)) x_o = F, Kh and N*I the local model's gains. Prints the\n"
      "poles of the lifted one-frame loop, its spectral radius, the steady-state force and proxy\n"
      "offset for a unit device step, and 2 % settling times from a lockstep simulation.\n"
      "Exit code 0 if stable, 1 if not.\n"
      "Example: fetouch stability --local-model p --k0 0.2 --kh 0.19   (rings: pole -0.95)");
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
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_flag("--json", o->json, "Print a JSON report");
  cmd->callback([o, &exit_code]() { exit_code = run_stability(*o); });
}

}  // namespace fetouch::app
