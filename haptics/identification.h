// On-line identification of a contact from the device's own signals, at the tick rate.
//
// Kelvin-Voigt (ContactIdentifier, run by the haptic loop for every contact). Along the contact's
// normal n, with the depth x measured from where the contact began (x = n . (p_touch - p), positive
// into the tissue), its rate v = dx/dt and the normal force f the device was sent (f = n . F):
//     f(k) = K x(k) + B v(k) + c
// c absorbs what the depth origin gets wrong (the surface moved under the hand, the force the
// contact started with). Recursive least squares with forgetting lambda on phi = [x, v, 1]:
//     e = f - phi' theta;  g = P phi / (lambda + phi' P phi);  theta += g e;
//     P = (P - g phi' P) / lambda
// (memory about 1 / (1 - lambda) ticks: 0.995 at 1 kHz is 0.2 s). Two guards against wind-up:
// a tick at which the depth moves less than excitation_m_per_s is not learnt from (a static hold
// carries no information about K, and forgetting without information makes P grow until noise
// moves theta: drift), and P is not divided by lambda once its trace passes max_covariance (a
// slow press excites x but hardly separates B from c). K is reported only once the contact has
// been learnt from over min_updates ticks and its depth has spanned min_span_m: before that it
// is a guess, and the loop does not compare it with anything.
//
// What K means: the slope of the force the hand was sent against its own depth, over the last
// ~0.2 s of motion. On a steady press through the multirate loop it is the stiffness the hand
// feels, which a faithful rendering makes the tissue's condensed normal stiffness (W_n^-1)_cc;
// the loop compares the two every frame (haptic_loop.h), so a wrong mesh, a wrong material or a
// late solver shows as a disagreement.
//
// Hunt-Crossley (HuntCrossleyIdentifier, for contacts whose force grows as a power of depth):
//     f = x^n (k + lambda_hc v),   x > 0
// is not linear in n, so it is identified by recursive Gauss-Newton (the recursive
// prediction-error method of Ljung and Soederstroem): the same update as above with phi the
// gradient of the prediction with respect to theta = [k, lambda_hc, n] at the current estimate,
//     phi = [x^n, x^n v, x^n (k + lambda_hc v) ln x].
// Diolaiti, Melchiorri and Stramigioli (IEEE T-RO 21(5), 2005) split the same law into two linear
// stages that hand each other their estimates; the joint gradient step needs no such split.
// It takes the excitation guard above.
//
// Units inside: millimetres and N (x, v scaled by 1e3), so that P starts well conditioned; the
// accessors answer in SI. Real-time safe: fixed-size Eigen, no allocation, no exceptions.
#pragma once

#include <Eigen/Core>

namespace fetouch::haptics {

struct IdentificationSettings {
  bool enabled = true;
  double forgetting = 0.99;               // lambda: a memory of 0.1 s at 1 kHz
  double initial_covariance = 1e3;        // P(0) = p0 I at every new contact (mm, N units)
  double max_covariance = 1e6;            // trace(P) above which P is no longer divided by lambda
  double excitation_m_per_s = 5e-4;       // |v| below which a tick is not learnt from
  int min_updates = 20;                   // learnt-from ticks before K is reported
  double min_span_m = 2e-4;               // depth span since the contact began before K is reported
};

// Throws std::invalid_argument naming the first value out of range.
void check(const IdentificationSettings& settings);

class ContactIdentifier {
 public:
  explicit ContactIdentifier(const IdentificationSettings& settings = {});

  // One tick: the device point, its velocity, the contact's outward normal and the force the device
  // was sent; in_contact false ends the contact (the next one starts afresh).
  void update(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity, const Eigen::Vector3d& normal,
              const Eigen::Vector3d& force, bool in_contact) noexcept;

  // K (N/m) and B (N s/m); valid(): enough excitation since the contact began for K to mean
  // something. Outside a contact all three keep their last values until the next contact.
  double stiffness_n_per_m() const { return theta_(0) * 1e3; }
  double damping_n_s_per_m() const { return theta_(1) * 1e3; }
  double offset_n() const { return theta_(2); }
  bool valid() const { return valid_; }
  bool in_contact() const { return touching_; }
  // The force the identified law gives at a depth and rate (SI), for checks and predictions.
  double predict_n(double depth_m, double rate_m_per_s) const {
    return theta_(0) * depth_m * 1e3 + theta_(1) * rate_m_per_s * 1e3 + theta_(2);
  }
  long updates() const { return updates_; }

 private:
  IdentificationSettings settings_;
  Eigen::Vector3d theta_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d p_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d touch_ = Eigen::Vector3d::Zero();
  bool touching_ = false, valid_ = false;
  long updates_ = 0;
  double min_depth_mm_ = 0, max_depth_mm_ = 0;
};

class HuntCrossleyIdentifier {
 public:
  // `initial_exponent`: n before anything is learnt (1.5: Hertz's sphere on a half-space).
  explicit HuntCrossleyIdentifier(const IdentificationSettings& settings = {}, double initial_exponent = 1.5);

  // One tick at depth x > 0 (m, from the contact point), rate v (m/s), force f (N). Ticks with
  // x or f not positive, or |v| under the excitation threshold, are not learnt from.
  void update(double depth_m, double rate_m_per_s, double force_n) noexcept;

  double stiffness() const;                      // k, N / m^n
  double damping() const;                        // lambda_hc, N s / m^(n+1)
  double exponent() const { return theta_(2); }  // n
  double predict_n(double depth_m, double rate_m_per_s) const;
  long updates() const { return updates_; }

 private:
  IdentificationSettings settings_;
  // In millimetres: f = X^n (a + b V), X = x / 1 mm, V = v / (1 mm/s); theta = [a, b, n].
  Eigen::Vector3d theta_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d p_ = Eigen::Matrix3d::Identity();
  long updates_ = 0;
};

}  // namespace fetouch::haptics
