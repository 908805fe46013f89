// The seam between the haptic side and the slow simulation (ARCHITECTURE.md section 2), shaped
// like the seed's D(z): once per frame the haptic loop hands over, for each contact, the device
// point and the force it rendered; one frame later it receives the deformed surface near each
// contact, the condensed compliance and the solve's status. Nothing here knows which simulation
// method answers: LinearEnvironment (analytic) and the FEM solver both implement it.
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "haptics/contact_frame.h"

namespace fetouch::haptics {

// What the haptic loop sends, per contact, at the first tick of a frame (the decimator).
struct ContactSample {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // the device point, m
  Eigen::Vector3d force = Eigen::Vector3d::Zero();     // force on the tissue, N (= -F n)
  double normal_force = 0;                             // F >= 0, along the held normal
  bool in_contact = false;
};

struct SolveStatus {
  bool converged = true;
  int iterations = 0;
  double residual = 0;
  double seconds = 0;
  std::string message;  // why not converged; empty otherwise
  // The environment solved otherwise than a lockstep replay would (real time: a solver that took
  // up a background factorisation later than lockstep does): from this answer on, the answers
  // agree with lockstep's within the solver's tolerance rather than bit for bit.
  bool differs_from_lockstep = false;
};

// The environment's answer for one frame.
struct EnvironmentUpdate {
  std::vector<ContactFrame> frames;  // per contact: the deformed surface near it
  // Condensed compliance W (3m x 3m, m/N): displacement of contact a's surface point per unit
  // force at contact b, couplings included. Symmetric positive definite.
  Eigen::MatrixXd compliance;
  Eigen::MatrixXd damping;  // optional (3m x 3m, frame-rate law as LinearEnvironment's B0), or empty
  SolveStatus status;
  long frame = -1;  // the frame j whose samples produced it
};

class Environment {
 public:
  virtual ~Environment() = default;
  virtual int contacts() const = 0;
  // The answer at rest, before any force: what the haptic loop holds during the first frame.
  virtual void initial(EnvironmentUpdate& out) = 0;
  // One frame: the samples of frame j in, the answer (applied from frame j + 1) out. `out` is
  // reused frame after frame, so an implementation can fill it without allocating. A frame that
  // fails (status.converged false) hands back the last converged answer, frames and compliance:
  // the state those samples' forces produced (the haptic loop keeps them as its Smith reference).
  virtual void solve(const std::vector<ContactSample>& samples, long frame, EnvironmentUpdate& out) = 0;
};

}  // namespace fetouch::haptics
