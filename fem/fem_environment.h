// The tissue solver behind the haptic seam (haptics/environment.h): one frame per call, the probes'
// forces in, the deformed contact frames and the condensed compliance out.
//
// Each contact is a patch of the solver (quasi_static_solver.h): the sample's force on the tissue
// becomes the patch force, Newton solves from the previous frame's state (warm start), and the
// update carries per contact the deformed patch point (centre + H u), the deformed normal, and
// W = H K^-1 H' (3m x 3m) at the new state. A failed frame is rolled back by the solver and
// reported (status.converged = false, why); the update then repeats the last good frames and W, so
// the haptic side keeps rendering the last good tissue.
//
// The patches follow the probes: before each frame's solve, a patch whose probe has moved along the
// surface (in the patch's tangent plane) by more than a quarter of its radius since the patch was
// placed is moved by as much over the reference surface, so a probe sliding over the tissue loads
// it where it is and its contact frame describes the surface under it.
#pragma once

#include <memory>
#include <vector>

#include "fem/quasi_static_solver.h"
#include "haptics/environment.h"

namespace fetouch::fem {

class FemEnvironment final : public haptics::Environment {
 public:
  // `solver` carries the mesh, material, supports and one contact patch per contact, in order.
  FemEnvironment(std::unique_ptr<QuasiStaticSolver> solver, const NewtonSettings& newton);

  int contacts() const override { return solver_->patches(); }
  void initial(haptics::EnvironmentUpdate& out) override;
  void solve(const std::vector<haptics::ContactSample>& samples, long frame, haptics::EnvironmentUpdate& out) override;

  QuasiStaticSolver& solver() { return *solver_; }
  void set_follow_probes(bool follow) { follow_ = follow; }
  long patch_moves() const { return patch_moves_; }
  // The last frame's solve: iterations, cuts, where its time went (studies read it).
  const SolveReport& last_report() const { return last_report_; }

 private:
  void describe(haptics::EnvironmentUpdate& out);

  std::unique_ptr<QuasiStaticSolver> solver_;
  NewtonSettings newton_;
  haptics::EnvironmentUpdate last_good_;
  bool follow_ = true;
  std::vector<Eigen::Vector3d> anchors_;  // each probe's position when its patch was last placed
  std::vector<Eigen::Vector3d> applied_;  // the force each patch carries (the last frame's)
  long patch_moves_ = 0;
  SolveReport last_report_;
};

}  // namespace fetouch::fem
