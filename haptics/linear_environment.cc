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
}

LinearEnvironment LinearEnvironment::scalar(double k0, double b0) {
  return LinearEnvironment(Eigen::MatrixXd::Constant(1, 1, k0), Eigen::MatrixXd::Constant(1, 1, b0));
}

const Eigen::VectorXd& LinearEnvironment::step(const Eigen::VectorXd& force) {
  surface_ = k_plus_b_.solve(force + damping_ * surface_);
  return surface_;
}

Eigen::MatrixXd LinearEnvironment::compliance() const {
  return stiffness_.ldlt().solve(Eigen::MatrixXd::Identity(stiffness_.rows(), stiffness_.cols()));
}

}  // namespace fetouch::haptics
