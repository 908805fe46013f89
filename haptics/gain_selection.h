// Robust gain selection: the local model's gains (Kh, I) for a tissue whose condensed stiffness is
// K (m x m for m contacts, in normal coordinates) and damping B, chosen inside the stability
// region with a margin on K.
//
// Uncertainty set. The solver's K is an estimate: the tissue is nonlinear and the next frame's
// stiffness differs. The gains must keep the loop stable for every true stiffness s K with
// s in [1 - m, 1 + m] (default m = 0.3). For several contacts the loop decouples along the
// eigenvectors v_i of K (exactly when B shares them, e.g. B = 0 or B proportional to K); each mode
// is a scalar loop with k = s lambda_i, b = v_i' B v_i and, for the Smith predictor, the nominal
// compliance w = 1 / lambda_i. Every eigenvalue is tested, so a soft coupled mode (two contacts
// pressing the same tissue) is never missed; tuning each contact alone would be.
// The robust spectral radius is the largest over the modes and `scale_samples` values of s.
//
// Criterion.
//   PI, PI + Smith: the steady force is K x_h whatever the gains, so the gains minimise the robust
//     spectral radius (fastest settling) over Kh in (0, 3 lambda_min], N I in (0, 2 lambda_min].
//   P, Smith: the rendered stiffness grows with Kh (K Kh / (K + Kh)) while the radius grows too, so
//     the gain is the largest Kh whose robust radius stays at or below `settle_radius`
//     (radius 0.5: within 2 % in six frames); if none does, the Kh of least radius.
// With a design hand (GainSelectionOptions::hand): the gains must also keep the loop with that
// hand in it stable (stability_analysis.h), at every (mode, scale) of the set, each contact held by
// its own copy of the hand. PI variants minimise the larger of the two radii (with and without the
// hand); P and Smith take the stiffest Kh whose radius without the hand is at most settle_radius
// and with it at most hand_settle_radius (a disturbance halves within 6 frames: 0.3 s at 20 Hz).
// The lifting without the hand holds the device still, so it cannot see that a PI rendering of a
// stiff tissue rings a hand of 0.3 kg on 300 N/m and 8 N s/m (radius 1.31 at 1 MPa, where the
// proof without the hand says 0.63): the design hand is the proof's hand.
// The result is always checked: `stable` is false (and the gains are the least unstable found)
// only when nothing in the search range is robustly stable.
#pragma once

#include <Eigen/Core>

#include <optional>

#include "haptics/devices.h"
#include "haptics/hold.h"
#include "haptics/local_model.h"

namespace fetouch::haptics {

struct GainSelectionOptions {
  double margin = 0.3;         // m: K may be off by a factor in [1 - m, 1 + m]
  int scale_samples = 5;       // values of s tested across that range, ends included
  double settle_radius = 0.5;  // P and Smith: the largest radius accepted for a stiffer rendering
  // The design hand the gains must be stable with, or none (the device held still).
  std::optional<HandParameters> hand;
  double period_s = 1e-3;            // T, for the hand's dynamics
  double hand_settle_radius = 0.89;  // P and Smith with a design hand: the largest radius accepted with it
};

struct GainSelection {
  LocalModelGains gains;
  double spectral_radius = 0;  // robust: the worst over the uncertainty set (and the design hand's loop)
  double hand_spectral_radius = 0;  // the loop with the design hand alone (0 without one)
  bool stable = false;
  int evaluations = 0;         // scalar loops evaluated
};

struct GainProblem {
  LocalModelKind local_model = LocalModelKind::pi;
  HoldKind hold = HoldKind::zoh;
  int ratio = 50;
  Eigen::MatrixXd stiffness;  // K, symmetric positive definite, m x m
  Eigen::MatrixXd damping;    // B, m x m, or empty for none
};

// Throws std::invalid_argument when K is not symmetric positive definite or B has the wrong size.
// `start`, if given (the gains in use), warm-starts the PI search: when they are robustly stable
// the coarse grid is skipped and the search refines from them with a small step. Runtime gain
// scheduling passes the previous frame's gains.
GainSelection select_gains(const GainProblem& problem, const GainSelectionOptions& options = {},
                           const LocalModelGains* start = nullptr);

// The robust spectral radius of given gains (the figure select_gains minimises or bounds).
double robust_spectral_radius(const GainProblem& problem, const LocalModelGains& gains,
                              const GainSelectionOptions& options = {});

}  // namespace fetouch::haptics
