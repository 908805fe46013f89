// LinearEnvironment: the analytic virtual environment of the seed, one solver frame per call.
//
// For m contacts, in normal coordinates (x_o: surface displacement along each contact's normal,
// F: force pushed into the surface along it), with K0 and B0 symmetric m x m matrices:
//
//     (K0 + B0 (1 - z^-1)) x_o = F,   i.e.   x_o(j) = (K0 + B0)^-1 (F(j) + B0 x_o(j-1)).
//
// State-space realization (state x_o(j-1), input F(j), output x_o(j)):
//     A = (K0 + B0)^-1 B0,   B = (K0 + B0)^-1,   C = A,   D = B.
// Timing (ARCHITECTURE.md section 3): the force sampled at the first tick of frame j goes in; the
// answer x_o(j) is used by the local model from the first tick of frame j + 1.
#pragma once

#include <Eigen/Dense>

namespace fetouch::haptics {

class LinearEnvironment {
 public:
  LinearEnvironment(const Eigen::MatrixXd& stiffness, const Eigen::MatrixXd& damping);

  // One frame: takes F(j), returns x_o(j) and remembers it.
  const Eigen::VectorXd& step(const Eigen::VectorXd& force);

  int contacts() const { return static_cast<int>(stiffness_.rows()); }
  const Eigen::MatrixXd& stiffness() const { return stiffness_; }
  const Eigen::MatrixXd& damping() const { return damping_; }
  // The condensed compliance the environment hands the local model: W = K0^-1.
  Eigen::MatrixXd compliance() const;

  const Eigen::VectorXd& surface() const { return surface_; }
  void set_surface(const Eigen::VectorXd& surface) { surface_ = surface; }

 private:
  Eigen::MatrixXd stiffness_, damping_;
  Eigen::LDLT<Eigen::MatrixXd> k_plus_b_;
  Eigen::VectorXd surface_, rhs_;
};

}  // namespace fetouch::haptics
