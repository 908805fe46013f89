#include "haptics/stability_analysis.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fetouch::haptics {

namespace {

// Packing of the frame-boundary state (see the header) into one vector and back. The loop is
// positioned at a frame boundary j >= 1, just before the promotion of the published answer.
struct StatePacking {
  int m = 1;
  bool integrator = false;
  int size() const { return (integrator ? 5 : 4) * m; }

  void unpack(const Eigen::VectorXd& x, NormalLoop& loop, FrameBoundary& state) const {
    state.answer_depth = x.segment(0, m);
    state.newest_depth = x.segment(m, m);
    state.answer_force = x.segment(2 * m, m);
    state.newest_force = x.segment(3 * m, m);
    state.integrator = integrator ? Eigen::VectorXd(x.segment(4 * m, m)) : Eigen::VectorXd::Zero(m);
    loop.set_frame_boundary(state);
  }

  void pack(const NormalLoop& loop, FrameBoundary& state, Eigen::Ref<Eigen::VectorXd> x) const {
    loop.frame_boundary(state);
    x.segment(0, m) = state.answer_depth;
    x.segment(m, m) = state.newest_depth;
    x.segment(2 * m, m) = state.answer_force;
    x.segment(3 * m, m) = state.newest_force;
    if (integrator) x.segment(4 * m, m) = state.integrator;
  }
};

}  // namespace

LoopParameters LoopParameters::scalar(LocalModelKind kind, HoldKind hold, int ratio, double k0,
                                      double b0, double kh, double integral) {
  LoopParameters p;
  p.local_model = kind;
  p.hold = hold;
  p.ratio = ratio;
  p.stiffness = Eigen::MatrixXd::Constant(1, 1, k0);
  p.damping = Eigen::MatrixXd::Constant(1, 1, b0);
  p.gains = {kh, integral};
  return p;
}

NormalLoop make_loop(const LoopParameters& p) { return NormalLoop(p); }

namespace {

// The rows of the hand's state per contact: one_mass (x_d, v_d), stylus (x_d, v_d, x_h, v_h).
int hand_rows(const HandParameters& hand) { return hand.model == HandModelKind::one_mass ? 2 : 4; }

}  // namespace

StabilityResult analyse(const LoopParameters& p) {
  const int m = static_cast<int>(p.stiffness.rows());
  NormalLoop loop(p);
  Eigen::VectorXd device = Eigen::VectorXd::Zero(m), velocity = Eigen::VectorXd::Zero(m);
  for (int i = 0; i < p.ratio; ++i) loop.tick(device, velocity);  // to a frame boundary, j = 1
  FrameBoundary boundary;

  const StatePacking packing{m, has_integrator(p.local_model)};
  const int rows = p.hand ? hand_rows(*p.hand) : 0;
  const int loop_size = packing.size(), n = loop_size + rows * m;
  Eigen::Matrix4d phi = Eigen::Matrix4d::Identity();
  Eigen::Matrix<double, 4, 3> gamma = Eigen::Matrix<double, 4, 3>::Zero();
  if (p.hand) hand_transition(*p.hand, 1.0, p.period_s, phi, gamma);
  Eigen::Matrix<double, 4, Eigen::Dynamic> hands(4, m);  // per contact: x_d, v_d, x_h, v_h
  StabilityResult result;
  result.monodromy.resize(n, n);
  for (int c = 0; c < n; ++c) {
    const Eigen::VectorXd unit = Eigen::VectorXd::Unit(n, c);
    packing.unpack(unit.head(loop_size), loop, boundary);
    hands.setZero();
    for (int k = 0; k < m; ++k) hands.col(k).head(rows) = unit.segment(loop_size + rows * k, rows);
    for (int i = 0; i < p.ratio; ++i) {
      device = hands.row(0).transpose();  // still (zero) without a hand
      velocity = hands.row(1).transpose();
      const Eigen::VectorXd& force = loop.tick(device, velocity);
      // The rendered force pushes the device back out of the tissue: -F along the penetration.
      if (p.hand)
        for (int k = 0; k < m; ++k) hands.col(k) = phi * hands.col(k) - gamma.col(0) * force(k);
    }
    packing.pack(loop, boundary, result.monodromy.col(c).head(loop_size));
    for (int k = 0; k < m; ++k) result.monodromy.col(c).segment(loop_size + rows * k, rows) = hands.col(k).head(rows);
  }

  Eigen::EigenSolver<Eigen::MatrixXd> eigen(result.monodromy, /*computeEigenvectors=*/false);
  for (int i = 0; i < n; ++i) result.poles.push_back(eigen.eigenvalues()[i]);
  std::sort(result.poles.begin(), result.poles.end(),
            [](auto a, auto b) { return std::abs(a) > std::abs(b); });
  result.spectral_radius = result.poles.empty() ? 0 : std::abs(result.poles.front());
  return result;
}

int closed_form_coefficients(LocalModelKind kind, HoldKind hold, int ratio, double k0, double b0,
                             const LocalModelGains& gains, double c[4]) noexcept {
  const double kh = gains.proportional, i = gains.integral, n = ratio;
  const auto set = [c](std::initializer_list<double> values) {
    int count = 0;
    for (double v : values) c[count++] = v;
    return count;
  };
  switch (kind) {
    case LocalModelKind::p:
      if (hold == HoldKind::zoh) return set({k0 + b0, kh - b0});
      return set({k0 + b0, -b0, kh});
    case LocalModelKind::pi:
      if (hold == HoldKind::zoh) return set({k0 + b0, kh - k0 - 2 * b0, b0 - kh + n * i});
      return set({k0 + b0, -(k0 + 2 * b0), kh + b0 + i * (n - 1) / 2, i * (n + 1) / 2 - kh});
    default:
      return 0;
  }
}

std::vector<double> characteristic_polynomial(const LoopParameters& p) {
  if (p.stiffness.rows() != 1)
    throw std::invalid_argument("closed forms exist for one contact (scalar K0, B0) only");
  double c[4];
  const int count = closed_form_coefficients(p.local_model, p.hold, p.ratio, p.stiffness(0, 0), p.damping(0, 0), p.gains, c);
  if (count == 0) throw std::invalid_argument("no closed form for the Smith-predictor local models");
  return std::vector<double>(c, c + count);
}

std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& c) {
  using C = std::complex<double>;
  if (c.size() == 2) return {C(-c[1] / c[0], 0)};
  if (c.size() == 3) {
    const double a = c[0], b = c[1], d = c[2];
    const C root = std::sqrt(C(b * b - 4 * a * d, 0));
    // The form that avoids cancellation: q = -(b + sign(b) sqrt(disc)) / 2, roots q/a and d/q.
    const C q = -0.5 * (C(b, 0) + (b >= 0 ? root : -root));
    if (std::abs(q) == 0) return {C(0, 0), C(0, 0)};
    return {q / a, C(d, 0) / q};
  }
  if (c.size() == 4) {
    Eigen::Matrix3d companion = Eigen::Matrix3d::Zero();
    companion(0, 0) = -c[1] / c[0];
    companion(0, 1) = -c[2] / c[0];
    companion(0, 2) = -c[3] / c[0];
    companion(1, 0) = 1;
    companion(2, 1) = 1;
    Eigen::EigenSolver<Eigen::Matrix3d> eigen(companion, false);
    return {eigen.eigenvalues()[0], eigen.eigenvalues()[1], eigen.eigenvalues()[2]};
  }
  throw std::invalid_argument("polynomial_roots: degrees 1 to 3 only");
}

bool jury_stable(const std::vector<double>& c) {
  // Normalise to a positive leading coefficient.
  std::vector<double> a = c;
  if (a[0] < 0)
    for (double& v : a) v = -v;
  if (a.size() == 2) return std::abs(a[1]) < a[0];
  if (a.size() == 3) {
    const double a2 = a[0], a1 = a[1], a0 = a[2];
    return std::abs(a0) < a2 && a2 + a1 + a0 > 0 && a2 - a1 + a0 > 0;
  }
  if (a.size() == 4) {
    // a3 z^3 + a2 z^2 + a1 z + a0: P(1) > 0, -P(-1) > 0, |a0| < a3, and |b0| > |b2| with
    // b0 = a0^2 - a3^2, b2 = a0 a2 - a1 a3 (Jury's table, third order).
    const double a3 = a[0], a2 = a[1], a1 = a[2], a0 = a[3];
    const double p1 = a3 + a2 + a1 + a0, pm1 = -a3 + a2 - a1 + a0;
    const double b0 = a0 * a0 - a3 * a3, b2 = a0 * a2 - a1 * a3;
    return p1 > 0 && -pm1 > 0 && std::abs(a0) < a3 && std::abs(b0) > std::abs(b2);
  }
  throw std::invalid_argument("jury_stable: degrees 1 to 3 only");
}

}  // namespace fetouch::haptics
