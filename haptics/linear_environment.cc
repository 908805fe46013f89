#include "haptics/linear_environment.h"

#include <stdexcept>

namespace fetouch::haptics {

LinearEnvironment::LinearEnvironment(const Eigen::MatrixXd& stiffness, const Eigen::MatrixXd& damping)
    : stiffness_(stiffness), damping_(damping) {
  if (stiffness.rows() != stiffness.cols() || damping.rows() != stiffness.rows() ||
      damping.cols() != stiffness.cols())
    throw std::invalid_argument("LinearEnvironment: K0 and B0 must be square and of one size");
  k_plus_b_.compute(stiffness_ + damping_);
  surface_ = Eigen::VectorXd::Zero(stiffness.rows());
  rhs_ = Eigen::VectorXd::Zero(stiffness.rows());
}

const Eigen::VectorXd& LinearEnvironment::step(const Eigen::VectorXd& force) {
  // Into preallocated vectors: in lockstep this runs inside the tick that decimates.
  rhs_.noalias() = damping_ * surface_;
  rhs_ += force;
  surface_ = k_plus_b_.solve(rhs_);
  return surface_;
}

Eigen::MatrixXd LinearEnvironment::compliance() const {
  return stiffness_.ldlt().solve(Eigen::MatrixXd::Identity(stiffness_.rows(), stiffness_.cols()));
}

}  // namespace fetouch::haptics
