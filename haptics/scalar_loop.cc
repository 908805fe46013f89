#include "haptics/scalar_loop.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <complex>

#include "haptics/stability_analysis.h"

namespace fetouch::haptics {

namespace {

using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4>;

double quadratic_max_root_modulus(double a2, double a1, double a0) {
  const double disc = a1 * a1 - 4 * a2 * a0;
  if (disc < 0) return std::sqrt(std::abs(a0 / a2));  // complex pair: |z|^2 = a0 / a2
  const double q = -0.5 * (a1 + std::copysign(std::sqrt(disc), a1));
  if (q == 0) return 0;
  return std::max(std::abs(q / a2), std::abs(a0 / q));
}

// One frame of the recurrence from state x, summed in closed form. Within a frame the held
// surface and reference force are affine in the tick index i (constant for ZOH), so with
//   g = 1 / (1 + Kh w)   (w = 0 without the predictor, g = 1),   u(i) = -x(i) + w r(i),
// the force is F(i) = g (Kh u(i) + s(i)), the penetration e(i) = g u(i) - w g s(i) (using
// 1 - w g Kh = g), and the integrator s(i+1) = a s(i) + I g u(i) with a = 1 - I w g. Hence
//   s(N) = a^N s(0) + I g (S0 u(0) + S1 (u(N) - u(0)) / N),  S0 = sum a^(N-1-i),  S1 = sum i a^(N-1-i).
// The sums take one pass over N per evaluation, whatever the state size.
struct Recurrence {
  const ScalarLoop& p;
  bool integrator, predictor;
  double gain, growth, s0, s1;  // g, a^N, S0, S1

  Recurrence(const ScalarLoop& loop)
      : p(loop), integrator(has_integrator(loop.local_model)), predictor(has_predictor(loop.local_model)) {
    const double kh = p.gains.proportional, w = predictor ? p.compliance : 0.0;
    gain = 1.0 / (1.0 + kh * w);
    const double a = integrator ? 1.0 - p.gains.integral * w * gain : 1.0;
    growth = 1, s0 = 0, s1 = 0;
    for (int i = p.ratio - 1; i >= 0; --i) {  // growth = a^(N-1-i) at step i
      s0 += growth;
      s1 += i * growth;
      growth *= a;
    }
  }

  void frame(const double* x, double* y) const {
    const double ps = x[0], h = x[1], pf = x[2], f = x[3], s = x[4];
    const double kh = p.gains.proportional, w = predictor ? p.compliance : 0.0;
    const bool zoh = p.hold == HoldKind::zoh;
    const double u_start = zoh ? -ps + w * pf : -h + w * f;  // u(0)
    const double u_end = -ps + w * pf;                        // u(N): the ramp's end (FOH)
    const double force = gain * (kh * u_start + (integrator ? s : 0.0));
    y[0] = (force + p.damping * ps) / (p.stiffness + p.damping);
    y[1] = ps;
    y[2] = force;
    y[3] = pf;
    y[4] = integrator ? growth * s + p.gains.integral * gain *
                                         (s0 * u_start + (zoh ? 0.0 : s1 * (u_end - u_start) / p.ratio))
                      : 0.0;
  }
};

}  // namespace

namespace {

// The largest real root of a3 z^3 + a2 z^2 + a1 z + a0 (a3 != 0): Cardano's formula (the
// trigonometric form when all three roots are real), polished by two Newton steps.
double cubic_largest_real_root(double a3, double a2, double a1, double a0) {
  const double c2 = a2 / a3, c1 = a1 / a3, c0 = a0 / a3;
  // Depressed cubic t^3 + p t + q with z = t - c2/3.
  const double shift = c2 / 3;
  const double p = c1 - c2 * shift, q = 2 * shift * shift * shift - shift * c1 + c0;
  const double half_q = q / 2, third_p = p / 3;
  const double disc = half_q * half_q + third_p * third_p * third_p;
  double t;
  if (disc >= 0) {
    const double root = std::sqrt(disc);
    t = std::cbrt(-half_q + root) + std::cbrt(-half_q - root);
  } else {  // three real roots: trigonometric form, the largest
    const double r = std::sqrt(-third_p);
    t = 2 * r * std::cos(std::acos(std::clamp(-half_q / (r * r * r), -1.0, 1.0)) / 3);
  }
  double z = t - shift;
  for (int it = 0; it < 2; ++it) {
    const double value = ((z + c2) * z + c1) * z + c0, slope = (3 * z + 2 * c2) * z + c1;
    if (slope != 0) z -= value / slope;
  }
  return z;
}

// max |y + shift| over the roots y of y^2 + b y + c (complex b, c allowed).
double shifted_quadratic_max_modulus(std::complex<double> b, std::complex<double> c, double shift) {
  const std::complex<double> root = std::sqrt(b * b - 4.0 * c);
  const std::complex<double> y1 = (-b + root) / 2.0, y2 = (-b - root) / 2.0;
  return std::max(std::abs(y1 + shift), std::abs(y2 + shift));
}

// max |root| of the monic quartic z^4 + a z^3 + b z^2 + c z + d by Ferrari's method: with
// z = y - a/4, y^4 + p y^2 + q y + r = (y^2 + p/2 + m)^2 - (sqrt(2m) y - q / (2 sqrt(2m)))^2 for
// m a positive root of the resolvent 8m^3 + 8p m^2 + (2p^2 - 8r) m - q^2.
double quartic_max_root_modulus(double a, double b, double c, double d) {
  const double shift = -a / 4;
  const double p = b - 3 * a * a / 8, q = c - a * b / 2 + a * a * a / 8;
  const double r = d - a * c / 4 + a * a * b / 16 - 3 * a * a * a * a / 256;
  const double scale = 1 + std::abs(p) + std::sqrt(std::abs(r));
  if (std::abs(q) < 1e-14 * scale * std::sqrt(scale)) {  // biquadratic: y^2 = t, t^2 + p t + r = 0
    const std::complex<double> root = std::sqrt(std::complex<double>(p * p - 4 * r, 0));
    double best = 0;
    for (const std::complex<double> t : {(-p + root) / 2.0, (-p - root) / 2.0}) {
      const std::complex<double> y = std::sqrt(t);
      best = std::max({best, std::abs(y + shift), std::abs(-y + shift)});
    }
    return best;
  }
  const double m = cubic_largest_real_root(8, 8 * p, 2 * p * p - 8 * r, -q * q);
  const double s = std::sqrt(2 * std::max(m, 0.0));
  if (s == 0) return std::nan("");
  const double first = shifted_quadratic_max_modulus(s, p / 2 + m - q / (2 * s), shift);
  const double second = shifted_quadratic_max_modulus(-s, p / 2 + m + q / (2 * s), shift);
  return std::max(first, second);
}

}  // namespace

double cubic_max_root_modulus(double a3, double a2, double a1, double a0) {
  const double c2 = a2 / a3, c1 = a1 / a3;
  const double z = cubic_largest_real_root(a3, a2, a1, a0);
  // Deflate: z^3 + c2 z^2 + c1 z + c0 = (z - root)(z^2 + d1 z + d0).
  const double d1 = c2 + z, d0 = c1 + z * d1;
  return std::max(std::abs(z), quadratic_max_root_modulus(1, d1, d0));
}

double recurrence_spectral_radius(const ScalarLoop& p) {
  const Recurrence recurrence(p);
  // Reduced coordinates. ZOH never reads h or f. FOH reads them only through u(0) = -h + w f, so
  // the state v = -h + w f replaces both (the dropped direction is an eigenvalue 0): with the
  // frame's outputs h' = ps and f' = pf, v' = -ps + w pf. Reduced: [ps, pf, v (FOH), s (PI)].
  const bool foh = p.hold == HoldKind::foh;
  const double w = recurrence.predictor ? p.compliance : 0.0;
  int n = 2;
  const int v_index = foh ? n++ : -1;
  const int s_index = recurrence.integrator ? n++ : -1;
  SmallMatrix phi(n, n);
  for (int a = 0; a < n; ++a) {
    double x[5] = {0, 0, 0, 0, 0}, y[5];
    if (a == 0) x[0] = 1;
    if (a == 1) x[2] = 1;
    if (a == v_index) x[1] = -1;  // h = -1, f = 0: v = 1
    if (a == s_index) x[4] = 1;
    recurrence.frame(x, y);
    phi(0, a) = y[0];
    phi(1, a) = y[2];
    if (v_index >= 0) phi(v_index, a) = -y[1] + w * y[3];
    if (s_index >= 0) phi(s_index, a) = y[4];
  }
  if (n == 2) {
    const double trace = phi.trace(), det = phi(0, 0) * phi(1, 1) - phi(0, 1) * phi(1, 0);
    return quadratic_max_root_modulus(1, -trace, det);
  }
  if (n == 3) {
    // Characteristic polynomial z^3 - tr z^2 + (sum of principal 2x2 minors) z - det.
    const double trace = phi.trace();
    const double minors = phi(0, 0) * phi(1, 1) - phi(0, 1) * phi(1, 0) + phi(0, 0) * phi(2, 2) -
                          phi(0, 2) * phi(2, 0) + phi(1, 1) * phi(2, 2) - phi(1, 2) * phi(2, 1);
    const double det = phi.determinant();
    return cubic_max_root_modulus(1, -trace, minors, -det);
  }
  // n == 4 (PI variants with FOH): the characteristic polynomial by Faddeev-LeVerrier,
  // z^4 + c3 z^3 + c2 z^2 + c1 z + c0, then Ferrari; the general eigenvalue solver if that fails.
  const Eigen::Matrix4d a = phi;
  Eigen::Matrix4d mk = a;
  const double c3 = -mk.trace();
  mk = a * (mk + c3 * Eigen::Matrix4d::Identity());
  const double c2 = -mk.trace() / 2;
  mk = a * (mk + c2 * Eigen::Matrix4d::Identity());
  const double c1 = -mk.trace() / 3;
  mk = a * (mk + c1 * Eigen::Matrix4d::Identity());
  const double c0 = -mk.trace() / 4;
  const double radius = quartic_max_root_modulus(c3, c2, c1, c0);
  if (std::isfinite(radius)) return radius;
  Eigen::EigenSolver<Eigen::Matrix4d> eigen(a, /*computeEigenvectors=*/false);
  double general = 0;
  for (int i = 0; i < 4; ++i) general = std::max(general, std::abs(eigen.eigenvalues()[i]));
  return general;
}

ScalarHand::ScalarHand(const HandParameters& hand, double period_s)
    : rows(hand.model == HandModelKind::one_mass ? 2 : 4) {
  Eigen::Matrix<double, 4, 3> gamma;
  hand_transition(hand, 1.0, period_s, phi, gamma);
  force = gamma.col(0);
}

double hand_spectral_radius(const ScalarLoop& p, const ScalarHand& hand) {
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 9, 9>;
  const bool integrator = has_integrator(p.local_model), predictor = has_predictor(p.local_model);
  const bool zoh = p.hold == HoldKind::zoh;
  const double kh = p.gains.proportional, w = predictor ? p.compliance : 0.0;
  const int loop_size = integrator ? 5 : 4, n = loop_size + hand.rows;
  // Row or column a of the map is entry slot(a) of the full state [ps, h, pf, f, s, hand]: the
  // integrator's entry is skipped without one.
  const auto slot = [loop_size](int a) { return a < loop_size ? a : 5 + (a - loop_size); };
  Matrix phi(n, n);
  for (int a = 0; a < n; ++a) {
    double x[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    x[slot(a)] = 1;
    const double ps = x[0], h = x[1], pf = x[2], f = x[3];
    double s = x[4];
    Eigen::Vector4d state(x[5], x[6], x[7], x[8]);
    double pending_surface = 0, pending_force = 0;
    // The promotion at the frame's first tick: (ps, pf) become the newest, (h, f) the previous.
    for (int i = 0; i < p.ratio; ++i) {
      const double t = zoh ? 1.0 : static_cast<double>(i) / p.ratio;
      const double held = h + t * (ps - h), reference = f + t * (pf - f);
      const double e = state(0) - held;
      double force, error = e;
      if (predictor) {
        force = (kh * (e + w * reference) + (integrator ? s : 0.0)) / (1 + kh * w);
        error = e - w * (force - reference);
      } else {
        force = kh * e + (integrator ? s : 0.0);
      }
      if (integrator) s += p.gains.integral * error;
      if (i == 0) pending_force = force, pending_surface = (force + p.damping * ps) / (p.stiffness + p.damping);
      state = hand.phi * state - hand.force * force;
    }
    const double y[9] = {pending_surface, ps, pending_force, pf, s, state(0), state(1), state(2), state(3)};
    for (int b = 0; b < n; ++b) phi(b, a) = y[slot(b)];
  }
  Eigen::EigenSolver<Matrix> eigen(phi, /*computeEigenvectors=*/false);
  return eigen.eigenvalues().cwiseAbs().maxCoeff();
}

double scalar_spectral_radius(const ScalarLoop& p) {
  double c[4];
  switch (closed_form_coefficients(p.local_model, p.hold, p.ratio, p.stiffness, p.damping, p.gains, c)) {
    case 2: return std::abs(c[1] / c[0]);
    case 3: return quadratic_max_root_modulus(c[0], c[1], c[2]);
    case 4: return cubic_max_root_modulus(c[0], c[1], c[2], c[3]);
    default: return recurrence_spectral_radius(p);
  }
}

}  // namespace fetouch::haptics
