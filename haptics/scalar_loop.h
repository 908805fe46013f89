// One contact's multirate loop reduced to its scalar frame recurrence, for the inner loops of gain
// selection and stability regions, where the general analysis (stability_analysis.h, which runs
// the Eigen loop itself) would cost too much per evaluation.
//
// The recurrence is a second, compact implementation of the timing convention of
// ARCHITECTURE.md section 3 (tests check it against the general analysis). With the device still
// (x_h = 0), the frame-boundary state just before frame j's promotion is
//     X = [ps, h, pf, f, s] = [x_o(j-1), x_o(j-2), F((j-1)N), F((j-2)N), s(jN)],
// and tick i of the frame, with x the held surface and r the held reference force, computes
//     P, PI:        F = -Kh x + s,                          e = -x
//     Smith:        F = (Kh (-x + w r) + s) / (1 + Kh w),   e = -x - w (F - r)
//     integrator:   s <- s + I e            (PI and PI + Smith)
//     i == 0:       pf' = F,  ps' = (F + b ps) / (k + b)    (decimation and the environment)
// For ZOH, h and f never reach the loop (their columns are zero) and the state shrinks to
// [ps, pf, s]; for FOH they enter only as v = -h + w f, and the state is [ps, pf, v, s]. The frame is summed in closed form (scalar_loop.cc). For P and PI the closed-form
// polynomials of stability_analysis.h are cheaper still.
#pragma once

#include <Eigen/Core>

#include "haptics/devices.h"
#include "haptics/hold.h"
#include "haptics/local_model.h"

namespace fetouch::haptics {

struct ScalarLoop {
  LocalModelKind local_model = LocalModelKind::p;
  HoldKind hold = HoldKind::zoh;
  int ratio = 50;          // N
  double stiffness = 1;    // k (K0 of this mode)
  double damping = 0;      // b
  double compliance = 1;   // w, the predictor's compliance (Smith variants)
  LocalModelGains gains;   // Kh, I
};

// Spectral radius of the one-frame map, by the recurrence above (any local model and hold).
double recurrence_spectral_radius(const ScalarLoop& loop);

// The same figure by the cheapest exact route: closed-form polynomial roots for P and PI, the
// recurrence for the Smith variants. No heap allocation.
double scalar_spectral_radius(const ScalarLoop& loop);

// A hand holding the device (devices.h), stepped over one tick with the force held: the rows of its
// state (2: x_d, v_d; 4 for the stylus: and x_h, v_h), exp(A T) and the column of the force.
struct ScalarHand {
  int rows = 2;
  Eigen::Matrix4d phi = Eigen::Matrix4d::Identity();
  Eigen::Vector4d force = Eigen::Vector4d::Zero();

  ScalarHand() = default;
  ScalarHand(const HandParameters& hand, double period_s);
};

// The spectral radius of the one-frame map of the loop with the hand in it (stability_analysis.h:
// the device is the hand's x_d, pushed back by -F each tick), by the tick recurrence above run
// from each unit state [ps, h, pf, f, s (PI variants), hand]: a second implementation of
// analyse() with a hand, for the gain selection's inner loop (tests compare the two). No heap
// allocation.
double hand_spectral_radius(const ScalarLoop& loop, const ScalarHand& hand);

// max |root| of a3 z^3 + a2 z^2 + a1 z + a0 (a3 != 0), without allocation: one real root by
// Cardano's formula polished by Newton, then the deflated quadratic.
double cubic_max_root_modulus(double a3, double a2, double a1, double a0);

}  // namespace fetouch::haptics
