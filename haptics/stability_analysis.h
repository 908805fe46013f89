// Stability of the multirate loop by lifting: the loop is N-periodic at the tick rate, so over one
// frame it is a time-invariant linear map of its frame-boundary state, X(j+1) = Phi X(j) (the
// monodromy matrix). The loop is stable iff the spectral radius of Phi is below 1.
//
// Phi is built column by column by running the devices' own loop (haptic_loop.h, in normal
// coordinates on the linear tissue: normal_loop.h) for one frame from each unit state with the
// device held still (x_h = 0); the analysis cannot disagree with the devices about timing, the
// hold, the gain blend or anything else between the local model and the device. The
// frame-boundary state, for m contacts, is
//   X = [x_o(j-1), x_o(j-2), F((j-1)N), F((j-2)N), s(jN)]      (s only for the PI variants),
// of which x_o(j-2) and the forces are pure delays for some variants: they add zero poles only.
//
// With a hand (LoopParameters::hand), the device is no longer held still: every contact's device
// is held by its own copy of the hand model (devices.h: one mass on the grip's spring and damper,
// or the two-stage stylus), linearised about the contact's operating point (the target still, the
// contact never lost), pushed back by the force the loop renders and stepped exactly over each
// tick with that force held (the operator device's own transition, hand_transition). The hand's
// state (x_d, v_d, and x_h, v_h for the stylus, per contact) joins X, so the verdict covers the
// loop that a hand closes: the proof without the hand says nothing about a light, stiff, barely
// damped grip on a stiff tissue (Colgate: a sampled stiffness K is passive only for K < 2 b / T).
//
// Cross-checks with closed forms (ARCHITECTURE.md section 3), scalar K0, B0:
//   P,  ZOH:  (K0+B0) z + (Kh - B0)
//   P,  FOH:  (K0+B0) z^2 - B0 z + Kh
//   PI, ZOH:  (K0+B0) z^2 + (Kh - K0 - 2B0) z + (B0 - Kh + N I)
//   PI, FOH:  (K0+B0) z^3 - (K0+2B0) z^2 + (Kh + B0 + I (N-1)/2) z + (I (N+1)/2 - Kh)
// (the last from s(j+1) = s(j) - I sum_i x_held(jN+i) with the FOH ramp; derivation in
// docs/stability.md).
#pragma once

#include <Eigen/Dense>

#include <complex>
#include <optional>
#include <vector>

#include "haptics/devices.h"
#include "haptics/hold.h"
#include "haptics/local_model.h"
#include "haptics/normal_loop.h"

namespace fetouch::haptics {

// The loop (normal_loop.h: model, hold, N, K0, B0, gains, W, T) and who holds its devices.
struct LoopParameters : NormalLoopParameters {
  // The hand holding each contact's device, or none (the device held still: the proof without the
  // hand); period_s is T, which the hand's dynamics need.
  std::optional<HandParameters> hand;

  static LoopParameters scalar(LocalModelKind kind, HoldKind hold, int ratio, double k0, double b0,
                               double kh, double integral = 0);
};

struct StabilityResult {
  Eigen::MatrixXd monodromy;
  std::vector<std::complex<double>> poles;  // eigenvalues of the monodromy, largest first
  double spectral_radius = 0;
  bool stable() const { return spectral_radius < 1.0; }
};

// The lockstep loop these parameters describe, at rest; W defaults to the environment's K0^-1.
// (The hand is not part of it: whoever drives it moves the device.)
NormalLoop make_loop(const LoopParameters& parameters);

StabilityResult analyse(const LoopParameters& parameters);

// The closed-form characteristic polynomial (coefficients, highest power first) for scalar K0, B0
// and the P/PI local models with either hold; throws for the Smith variants or matrix parameters.
std::vector<double> characteristic_polynomial(const LoopParameters& parameters);

// The same coefficients without allocation, for inner loops: writes them to `c` and returns how
// many there are (2 to 4), or 0 for the Smith variants, which have no closed form here.
int closed_form_coefficients(LocalModelKind kind, HoldKind hold, int ratio, double k0, double b0,
                             const LocalModelGains& gains, double c[4]) noexcept;

// Roots of a polynomial (highest power first) of degree 1 to 3: closed forms for degrees 1 and 2,
// the companion matrix for 3.
std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& coefficients);

// Jury's test: all roots strictly inside the unit circle. Degrees 1 to 3.
bool jury_stable(const std::vector<double>& coefficients);

}  // namespace fetouch::haptics
