#include "haptics/linear_surface_environment.h"

#include <stdexcept>

namespace fetouch::haptics {

LinearSurfaceEnvironment::LinearSurfaceEnvironment(std::vector<ContactFrame> rest, const Eigen::MatrixXd& stiffness,
                                                   const Eigen::MatrixXd& damping)
    : rest_(std::move(rest)), law_(stiffness, damping), force_(Eigen::VectorXd::Zero(stiffness.rows())) {
  if (stiffness.rows() != 3 * static_cast<Eigen::Index>(rest_.size()))
    throw std::invalid_argument("LinearSurfaceEnvironment: the stiffness must be 3m x 3m for m contacts");
  compliance_ = law_.compliance();
}

LinearSurfaceEnvironment LinearSurfaceEnvironment::isotropic(std::vector<ContactFrame> rest, double k, double b) {
  const auto n = 3 * static_cast<Eigen::Index>(rest.size());
  return LinearSurfaceEnvironment(std::move(rest), k * Eigen::MatrixXd::Identity(n, n),
                                  b * Eigen::MatrixXd::Identity(n, n));
}

void LinearSurfaceEnvironment::set_stiffness(const Eigen::MatrixXd& stiffness) {
  LinearEnvironment changed(stiffness, law_.damping());
  changed.set_surface(law_.surface());
  law_ = std::move(changed);
  compliance_ = law_.compliance();
}

void LinearSurfaceEnvironment::set_reported_compliance(const Eigen::MatrixXd& compliance) {
  if (compliance.rows() != law_.stiffness().rows() || compliance.cols() != law_.stiffness().cols())
    throw std::invalid_argument("LinearSurfaceEnvironment: the reported compliance must be 3m x 3m");
  compliance_ = compliance;
}

void LinearSurfaceEnvironment::initial(EnvironmentUpdate& out) {
  out.frames = rest_;
  out.compliance = compliance_;
  out.damping = law_.damping();
  out.status = {};
  out.frame = -1;
}

void LinearSurfaceEnvironment::solve(const std::vector<ContactSample>& samples, long frame, EnvironmentUpdate& out) {
  const int m = contacts();
  for (int c = 0; c < m; ++c) force_.segment<3>(3 * c) = samples[c].force;
  const Eigen::VectorXd& u = law_.step(force_);
  out.frames.resize(m);
  for (int c = 0; c < m; ++c) {
    out.frames[c] = rest_[c];
    out.frames[c].point += u.segment<3>(3 * c);
  }
  out.compliance = compliance_;
  out.damping = law_.damping();
  out.status = {};
  out.status.iterations = 1;
  out.frame = frame;
}

}  // namespace fetouch::haptics
