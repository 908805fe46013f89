#include "haptics/step_response.h"

#include <cmath>
#include <stdexcept>


namespace fetouch::haptics {

namespace {

// The last time the series is farther than 2 % of the final value from it; -1 if still outside
// at the end of the run (or the final value is zero).
double settling_time(const std::vector<double>& y, double final_value, double period_s) {
  const double band = 0.02 * std::abs(final_value);
  if (band == 0 || y.empty()) return -1;
  if (std::abs(y.back() - final_value) > band) return -1;
  for (size_t k = y.size(); k-- > 0;)
    if (std::abs(y[k] - final_value) > band) return static_cast<double>(k + 1) * period_s;
  return 0;
}

}  // namespace

StepResponse simulate_step(const LoopParameters& p, double period_s, double duration_s) {
  if (p.stiffness.rows() != 1) throw std::invalid_argument("simulate_step: one contact only");
  const double k0 = p.stiffness(0, 0), kh = p.gains.proportional;
  NormalLoop loop = make_loop(p);

  StepResponse r;
  r.period_s = period_s;
  const bool integral = has_integrator(p.local_model);
  r.steady_force = integral ? k0 : k0 * kh / (k0 + kh);
  r.steady_surface = integral ? 1.0 : kh / (k0 + kh);
  const long ticks = static_cast<long>(std::ceil(duration_s / period_s));
  const Eigen::VectorXd device = Eigen::VectorXd::Ones(1);
  for (long k = 0; k < ticks; ++k) {
    const double f = loop.tick(device)(0);
    r.force.push_back(f);
    r.surface.push_back(loop.surface()(0));
    r.proxy.push_back(loop.held_surface()(0));  // the surface the local model rendered this tick
  }
  r.force_settling_s = settling_time(r.force, r.steady_force, period_s);
  r.surface_settling_s = settling_time(r.surface, r.steady_surface, period_s);
  return r;
}

}  // namespace fetouch::haptics
