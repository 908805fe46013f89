#include "haptics/local_model.h"

namespace fetouch::haptics {

namespace {
constexpr LocalModelKind kKinds[] = {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith};
constexpr const char* kNames[] = {"p", "pi", "smith", "pi_smith"};
}  // namespace

const char* to_string(LocalModelKind kind) {
  for (int i = 0; i < 4; ++i)
    if (kKinds[i] == kind) return kNames[i];
  return "?";
}

bool parse_local_model(const std::string& name, LocalModelKind& kind) {
  for (int i = 0; i < 4; ++i)
    if (name == kNames[i]) {
      kind = kKinds[i];
      return true;
    }
  return false;
}

LocalModel::LocalModel(LocalModelKind kind, int contacts)
    : kind_(kind),
      compliance_(Eigen::MatrixXd::Zero(contacts, contacts)),
      loop_matrix_(Eigen::MatrixXd::Identity(contacts, contacts)),
      loop_lu_(contacts),
      integrator_(Eigen::VectorXd::Zero(contacts)),
      force_(Eigen::VectorXd::Zero(contacts)),
      error_(Eigen::VectorXd::Zero(contacts)),
      rhs_(Eigen::VectorXd::Zero(contacts)),
      integrating_mask_(Eigen::VectorXd::Ones(contacts)) {}

void LocalModel::set_kind(LocalModelKind kind) noexcept {
  const bool had_integrator = has_integrator();
  kind_ = kind;
  if (has_integrator() && !had_integrator) integrator_.setZero();
  refactor();
}

void LocalModel::set_gains(const LocalModelGains& gains) {
  gains_ = gains;
  refactor();
}

void LocalModel::set_compliance(const Eigen::MatrixXd& compliance) {
  compliance_ = compliance;
  refactor();
}

void LocalModel::refactor() {
  if (!has_predictor()) return;
  loop_matrix_.setIdentity();
  loop_matrix_ += gains_.proportional * compliance_;
  loop_lu_.compute(loop_matrix_);
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
    force_ = loop_lu_.solve(rhs_);
    // The penetration behind the predicted surface, for the integrator.
    rhs_ = force_ - reference_force;
    error_.noalias() -= compliance_ * rhs_;
  } else {
    force_ = kh * error_;
    if (has_integrator()) force_ += integrator_;
  }
  if (has_integrator() && integrating_) {
    for (Eigen::Index c = 0; c < integrator_.size(); ++c) {
      const double step = gains_.integral * error_(c);
      // A held contact may still unwind (a step towards less force), never wind up further.
      if (integrating_mask_(c) > 0 || step * integrator_(c) < 0) integrator_(c) += step;
    }
    integrator_ = integrator_.cwiseMax(-integrator_limit_).cwiseMin(integrator_limit_);
  }
  if (unilateral_)
    for (Eigen::Index c = 0; c < force_.size(); ++c)
      if (!(force_(c) > 0)) force_(c) = 0, integrator_(c) = 0;
  return force_;
}

}  // namespace fetouch::haptics
