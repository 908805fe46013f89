// LinearEnvironment behind the Environment seam, in 3D: each contact sits on a tissue surface at
// rest (a ContactFrame), and the surface points move by u (3m) under the forces f on the tissue
// (3m) by the frame-rate law of linear_environment.h,
//     (K0 + B0 (1 - z^-1)) u = f,      K0, B0 symmetric 3m x 3m (couplings between contacts),
// the surface translating rigidly near each contact (normals and curvature keep their rest values).
// The condensed compliance it reports is W = K0^-1. It is the analytic reference for the 3D loop:
// projected on the normals it is the scalar loop of the seed (tests check this).
#pragma once

#include "haptics/environment.h"
#include "haptics/linear_environment.h"

namespace fetouch::haptics {

class LinearSurfaceEnvironment final : public Environment {
 public:
  LinearSurfaceEnvironment(std::vector<ContactFrame> rest, const Eigen::MatrixXd& stiffness,
                           const Eigen::MatrixXd& damping);

  // An isotropic, uncoupled tissue: K0 = k I and B0 = b I (3m x 3m).
  static LinearSurfaceEnvironment isotropic(std::vector<ContactFrame> rest, double stiffness_n_per_m,
                                            double damping_n_per_m = 0);

  int contacts() const override { return static_cast<int>(rest_.size()); }
  void initial(EnvironmentUpdate& out) override;
  void solve(const std::vector<ContactSample>& samples, long frame, EnvironmentUpdate& out) override;

  // A change of tissue (e.g. a stiffer region reached): takes effect at the next solve.
  void set_stiffness(const Eigen::MatrixXd& stiffness);
  // The compliance reported to the loop instead of K0^-1 (3m x 3m): a condensation that is off, as
  // a Smith predictor's model may be. Kept until the next set_stiffness.
  void set_reported_compliance(const Eigen::MatrixXd& compliance);

  // The frame-rate law's memory: the displacement u (3m) of the last answer, which B0 damps against.
  void set_displacement(const Eigen::VectorXd& u) { law_.set_surface(u); }

 private:
  std::vector<ContactFrame> rest_;
  LinearEnvironment law_;
  Eigen::MatrixXd compliance_;
  Eigen::VectorXd force_;
};

}  // namespace fetouch::haptics
