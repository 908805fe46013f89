// The multirate loop in lockstep (simulated time), for m contacts in normal coordinates: the
// seed's block diagram, local model -> decimator -> environment -> one-frame delay -> hold -> local
// model. Ticks have period T; a frame is N ticks. At tick k = jN + i:
//
//   1. if i == 0 and j > 0: the environment's answer to F((j-1)N) becomes the newest held value
//      (one frame delay), the previous newest moves back;
//   2. the hold gives x_held(k) and F_ref(k) (hold.h);
//   3. the local model gives F(k) (local_model.h);
//   4. if i == 0: decimation: F(jN) goes to the environment, whose answer waits for frame j + 1.
//
// The stability analysis (stability_analysis.h) lifts exactly this code over one frame, so the
// verdicts and the simulation cannot disagree about the timing. Same inputs, bit-identical outputs.
#pragma once

#include <Eigen/Dense>

#include "haptics/hold.h"
#include "haptics/linear_environment.h"
#include "haptics/local_model.h"

namespace fetouch::haptics {

// Everything the loop remembers between ticks, besides the blocks' own states.
struct MultirateState {
  Eigen::VectorXd held_newest, held_previous;    // x_o(j-1), x_o(j-2) during frame j
  Eigen::VectorXd force_newest, force_previous;  // the forces that produced them
  Eigen::VectorXd pending_surface, pending_force;  // the answer to F(jN), applied from frame j + 1
  long tick = 0;

  explicit MultirateState(int contacts = 1);
};

class MultirateLoop {
 public:
  MultirateLoop(LocalModel local_model, LinearEnvironment environment, HoldKind hold, int ratio);

  // One haptic tick with the device's penetration coordinates; returns the force F(k).
  const Eigen::VectorXd& tick(const Eigen::VectorXd& device) noexcept;

  int ratio() const { return ratio_; }
  int contacts() const { return environment_.contacts(); }
  HoldKind hold() const { return hold_; }
  const Eigen::VectorXd& held_surface() const { return held_; }  // x_held(k) of the last tick
  const Eigen::VectorXd& surface() const { return state_.held_newest; }
  MultirateState& state() { return state_; }
  LocalModel& local_model() { return local_model_; }
  LinearEnvironment& environment() { return environment_; }

 private:
  LocalModel local_model_;
  LinearEnvironment environment_;
  HoldKind hold_;
  int ratio_;
  MultirateState state_;
  Eigen::VectorXd held_, reference_;
};

}  // namespace fetouch::haptics
