// The response of one contact to a unit step of the device into the surface (x_h = 1 from tick 0),
// simulated in lockstep with the multirate loop, and the figures read off it.
#pragma once

#include <vector>

#include "haptics/stability_analysis.h"

namespace fetouch::haptics {

struct StepResponse {
  double period_s = 1e-3;
  // Per tick k (time k T, device x_h = 1): proxy (the held surface the local model rendered
  // against), surface x_o (the environment's newest answer) and force F.
  std::vector<double> proxy, surface, force;
  double steady_force = 0;    // closed form: K0 Kh/(K0 + Kh) for P and Smith, K0 for PI variants
  double steady_surface = 0;  // Kh/(K0 + Kh), or 1
  double force_settling_s = -1;    // 2 % settling time; -1 if it does not settle in the run
  double surface_settling_s = -1;
};

// Scalar parameters only. `duration_s` is the simulated time.
StepResponse simulate_step(const LoopParameters& parameters, double period_s, double duration_s);

}  // namespace fetouch::haptics
