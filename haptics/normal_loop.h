// The devices' loop (haptic_loop.h) in normal coordinates on the seed's linear tissue: the loop the
// stability analysis lifts (stability_analysis.h) and the step response simulates.
//
// m contacts side by side on one plane (normal +z), pressed along -z; a device's depth d is the
// penetration coordinate of the seed (x_h), its point (0.1 c, 0, -d). The tissue is
// LinearSurfaceEnvironment with K0, B0 (m x m, along the normals; the tangential directions held by
// a stiffness of K0's largest diagonal, which no normal force reaches), answered in lockstep.
// Everything between the local model and the device runs as on a device: the hold, the frame
// delay, the gain blend, the passivity layer (off), the safety layer (limits out of reach), the
// samples the tissue is pressed with. What differs from a device's session is only what the
// linear map leaves out: the contact holds on both sides (HapticLoopSettings::unilateral false),
// so a force may pull, and nothing clamps.
//
// Per tick k = jN + i, in these coordinates (ARCHITECTURE.md section 3):
//   1. if i == 0 and j > 0: the answer to F((j-1)N) becomes the newest held surface (one frame
//      delay), the previous newest moves back;
//   2. the hold gives x_held(k) and F_ref(k) (hold.h);
//   3. the local model gives F(k) (local_model.h) on e = d(k) - x_held(k);
//   4. if i == 0: F(jN) presses the tissue, whose answer waits for frame j + 1.
#pragma once

#include <Eigen/Dense>

#include <vector>

#include "haptics/haptic_loop.h"
#include "haptics/linear_surface_environment.h"

namespace fetouch::haptics {

struct NormalLoopParameters {
  LocalModelKind local_model = LocalModelKind::p;
  HoldKind hold = HoldKind::zoh;
  int ratio = 50;                  // N
  Eigen::MatrixXd stiffness;       // K0, m x m
  Eigen::MatrixXd damping;         // B0, m x m
  LocalModelGains gains;           // Kh, I (fixed: no scheduling)
  Eigen::MatrixXd compliance;      // W the tissue reports (the Smith predictor's); empty: K0^-1
  double period_s = 1e-3;
};

class NormalLoop {
 public:
  explicit NormalLoop(const NormalLoopParameters& parameters);
  NormalLoop(const NormalLoop&) = delete;
  NormalLoop& operator=(const NormalLoop&) = delete;

  // One tick with the devices' depths (m); returns the normal forces sent F(k). The velocities
  // (d'(k)) go to the layers that watch them; without them, backward differences.
  const Eigen::VectorXd& tick(const Eigen::VectorXd& depth);
  const Eigen::VectorXd& tick(const Eigen::VectorXd& depth, const Eigen::VectorXd& velocity);

  int contacts() const { return loop_.contacts(); }
  int ratio() const { return loop_.settings().ratio; }
  HoldKind hold() const { return loop_.hold(); }
  // x_held(k) of the last tick: the depth of the surface the local model rendered against.
  const Eigen::VectorXd& held_surface() const { return held_; }
  // The newest answer taken up (x_o(j-1) during frame j).
  const Eigen::VectorXd& surface() const { return surface_; }

  // The state between frames (haptic_loop.h's FrameBoundary), the tissue's memory included:
  // valid after a tick that decimated (the answer is published then).
  void frame_boundary(FrameBoundary& out) const { loop_.frame_boundary(out); }
  void set_frame_boundary(const FrameBoundary& state);

 private:
  const Eigen::VectorXd& finish(const std::vector<ContactOutput>& out);

  LinearSurfaceEnvironment environment_;
  HapticLoop loop_;
  LockstepSession session_;
  std::vector<Eigen::Vector3d> points_, velocities_;
  Eigen::VectorXd force_, held_, surface_, displacement_;
};

}  // namespace fetouch::haptics
