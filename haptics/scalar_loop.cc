#include "haptics/scalar_loop.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <complex>

namespace fetouch::haptics {

namespace {

using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 5, 5>;

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

double cubic_max_root_modulus(double a3, double a2, double a1, double a0) {
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
  } else {  // three real roots: trigonometric form, take the largest t
    const double r = std::sqrt(-third_p);
    t = 2 * r * std::cos(std::acos(std::clamp(-half_q / (r * r * r), -1.0, 1.0)) / 3);
  }
  double z = t - shift;
  for (int it = 0; it < 2; ++it) {  // Newton polish on the monic cubic
    const double value = ((z + c2) * z + c1) * z + c0, slope = (3 * z + 2 * c2) * z + c1;
    if (slope != 0) z -= value / slope;
  }
  // Deflate: z^3 + c2 z^2 + c1 z + c0 = (z - root)(z^2 + d1 z + d0).
  const double d1 = c2 + z, d0 = c1 + z * d1;
  return std::max(std::abs(z), quadratic_max_root_modulus(1, d1, d0));
}

double recurrence_spectral_radius(const ScalarLoop& p) {
  const Recurrence recurrence(p);
  // Active coordinates: ZOH never reads h or f.
  int active[5], n = 0;
  for (int c = 0; c < 5; ++c) {
    if (p.hold == HoldKind::zoh && (c == 1 || c == 3)) continue;
    if (!recurrence.integrator && c == 4) continue;
    active[n++] = c;
  }
  SmallMatrix phi(n, n);
  for (int a = 0; a < n; ++a) {
    double x[5] = {0, 0, 0, 0, 0}, y[5];
    x[active[a]] = 1;
    recurrence.frame(x, y);
    for (int b = 0; b < n; ++b) phi(b, a) = y[active[b]];
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
  Eigen::EigenSolver<SmallMatrix> eigen(phi, /*computeEigenvectors=*/false);
  double radius = 0;
  for (int i = 0; i < n; ++i) radius = std::max(radius, std::abs(eigen.eigenvalues()[i]));
  return radius;
}

double scalar_spectral_radius(const ScalarLoop& p) {
  const double k = p.stiffness, b = p.damping, kh = p.gains.proportional;
  const double i = p.gains.integral, n = p.ratio;
  switch (p.local_model) {
    case LocalModelKind::p:
      if (p.hold == HoldKind::zoh) return std::abs((kh - b) / (k + b));
      return quadratic_max_root_modulus(k + b, -b, kh);
    case LocalModelKind::pi:
      if (p.hold == HoldKind::zoh) return quadratic_max_root_modulus(k + b, kh - k - 2 * b, b - kh + n * i);
      return cubic_max_root_modulus(k + b, -(k + 2 * b), kh + b + i * (n - 1) / 2, i * (n + 1) / 2 - kh);
    default:
      return recurrence_spectral_radius(p);
  }
}

}  // namespace fetouch::haptics
