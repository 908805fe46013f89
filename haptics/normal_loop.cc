#include "haptics/normal_loop.h"

#include <stdexcept>

namespace fetouch::haptics {

namespace {

constexpr double kSpacingM = 0.1;  // between the contacts' rest points along x

std::vector<ContactFrame> rest_frames(int m) {
  std::vector<ContactFrame> rest(m);
  for (int c = 0; c < m; ++c) rest[c].point = Eigen::Vector3d(kSpacingM * c, 0, 0);
  return rest;
}

// A normal-coordinate m x m matrix as the 3m x 3m one of contacts along z, `tangential` on the
// tangential diagonal.
Eigen::MatrixXd along_normals(const Eigen::MatrixXd& normal, double tangential) {
  const Eigen::Index m = normal.rows();
  Eigen::MatrixXd full = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  for (Eigen::Index a = 0; a < m; ++a) {
    full(3 * a, 3 * a) = full(3 * a + 1, 3 * a + 1) = tangential;
    for (Eigen::Index b = 0; b < m; ++b) full(3 * a + 2, 3 * b + 2) = normal(a, b);
  }
  return full;
}

LinearSurfaceEnvironment make_environment(const NormalLoopParameters& p) {
  const Eigen::Index m = p.stiffness.rows();
  if (m < 1 || p.stiffness.cols() != m || p.damping.rows() != m || p.damping.cols() != m)
    throw std::invalid_argument("NormalLoop: K0 and B0 must be square, of one size, at least 1 x 1");
  const double tangential = p.stiffness.diagonal().cwiseAbs().maxCoeff();
  LinearSurfaceEnvironment environment(rest_frames(static_cast<int>(m)), along_normals(p.stiffness, tangential),
                                       along_normals(p.damping, 0));
  if (p.compliance.size()) {
    if (p.compliance.rows() != m || p.compliance.cols() != m)
      throw std::invalid_argument("NormalLoop: the compliance W must be m x m");
    environment.set_reported_compliance(along_normals(p.compliance, 1 / tangential));
  }
  return environment;
}

HapticLoopSettings settings_for(const NormalLoopParameters& p) {
  HapticLoopSettings s;
  s.local_model = p.local_model;
  s.hold = p.hold;
  s.ratio = p.ratio;
  s.period_s = p.period_s;
  s.gains = p.gains;
  s.schedule_gains = false;
  s.unilateral = false;
  s.passivity.mode = PassivityMode::off;
  s.identification.enabled = false;  // nothing here reads it, and it does not shape the force
  s.safety.max_force_n = 1e300;
  s.safety.max_force_rate_n_per_s = 1e300;
  s.safety.period_s = p.period_s;
  s.safety.watchdog_timeout_s = 1e300;
  return s;
}

}  // namespace

NormalLoop::NormalLoop(const NormalLoopParameters& p)
    : environment_(make_environment(p)),
      loop_(settings_for(p), initial_update(environment_)),
      session_(loop_, environment_),
      points_(loop_.contacts(), Eigen::Vector3d::Zero()),
      velocities_(loop_.contacts(), Eigen::Vector3d::Zero()),
      force_(Eigen::VectorXd::Zero(loop_.contacts())),
      held_(Eigen::VectorXd::Zero(loop_.contacts())),
      surface_(Eigen::VectorXd::Zero(loop_.contacts())),
      displacement_(Eigen::VectorXd::Zero(3 * loop_.contacts())) {}

const Eigen::VectorXd& NormalLoop::tick(const Eigen::VectorXd& depth) {
  for (int c = 0; c < contacts(); ++c) points_[c] = Eigen::Vector3d(kSpacingM * c, 0, -depth(c));
  return finish(session_.tick(points_));
}

const Eigen::VectorXd& NormalLoop::tick(const Eigen::VectorXd& depth, const Eigen::VectorXd& velocity) {
  for (int c = 0; c < contacts(); ++c) {
    points_[c] = Eigen::Vector3d(kSpacingM * c, 0, -depth(c));
    velocities_[c] = Eigen::Vector3d(0, 0, -velocity(c));
  }
  return finish(session_.tick(points_, velocities_));
}

const Eigen::VectorXd& NormalLoop::finish(const std::vector<ContactOutput>& out) {
  const FrameSlot& newest = loop_.newest();
  for (int c = 0; c < contacts(); ++c) {
    force_(c) = out[c].force.z();
    held_(c) = -points_[c].z() - out[c].penetration;
    surface_(c) = -newest.update.frames[c].point.z();
  }
  return force_;
}

void NormalLoop::set_frame_boundary(const FrameBoundary& state) {
  loop_.set_frame_boundary(state);
  // The tissue's memory is the answer it gave last: the published one.
  displacement_.setZero();
  for (int c = 0; c < contacts(); ++c) displacement_(3 * c + 2) = -state.answer_depth(c);
  environment_.set_displacement(displacement_);
}

}  // namespace fetouch::haptics
