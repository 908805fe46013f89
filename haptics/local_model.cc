#include "haptics/local_model.h"

namespace fetouch::haptics {

LocalModel::LocalModel(LocalModelKind kind, int contacts)
    : kind_(kind),
      compliance_(Eigen::MatrixXd::Zero(contacts, contacts)),
      loop_inverse_(Eigen::MatrixXd::Identity(contacts, contacts)),
      integrator_(Eigen::VectorXd::Zero(contacts)),
      force_(Eigen::VectorXd::Zero(contacts)),
      error_(Eigen::VectorXd::Zero(contacts)),
      rhs_(Eigen::VectorXd::Zero(contacts)) {}

void LocalModel::set_gains(const LocalModelGains& gains) {
  gains_ = gains;
  refactor();
}

void LocalModel::set_compliance(const Eigen::MatrixXd& compliance) {
  compliance_ = compliance;
  refactor();
}

void LocalModel::refactor() {
  const auto n = compliance_.rows();
  if (has_predictor())
    loop_inverse_ = (Eigen::MatrixXd::Identity(n, n) + gains_.proportional * compliance_).inverse();
  else
    loop_inverse_.setIdentity();
}

const Eigen::VectorXd& LocalModel::step(const Eigen::VectorXd& device,
                                        const Eigen::VectorXd& held_surface,
                                        const Eigen::VectorXd& reference_force) noexcept {
  const double kh = gains_.proportional;
  error_.noalias() = device - held_surface;
  if (has_predictor()) {
    rhs_.noalias() = compliance_ * reference_force;
    rhs_ += error_;
    rhs_ *= kh;
    if (has_integrator()) rhs_ += integrator_;
    force_.noalias() = loop_inverse_ * rhs_;
    // The penetration behind the predicted surface, for the integrator.
    rhs_ = force_ - reference_force;
    error_.noalias() -= compliance_ * rhs_;
  } else {
    force_ = kh * error_;
    if (has_integrator()) force_ += integrator_;
  }
  if (has_integrator()) {
    integrator_ += gains_.integral * error_;
    integrator_ = integrator_.cwiseMax(-integrator_limit_).cwiseMin(integrator_limit_);
  }
  return force_;
}

}  // namespace fetouch::haptics
