#include "haptics/identification.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace fetouch::haptics {

namespace {
constexpr double kMm = 1e3;  // m -> mm

void require(bool ok, const char* what, double value) {
  if (!ok) throw std::invalid_argument(std::string("identification: ") + what + " (got " + std::to_string(value) + ")");
}
}  // namespace

void check(const IdentificationSettings& s) {
  require(std::isfinite(s.forgetting) && s.forgetting > 0.5 && s.forgetting <= 1,
          "forgetting must lie in (0.5, 1]", s.forgetting);
  require(std::isfinite(s.initial_covariance) && s.initial_covariance > 0, "initial_covariance must be positive",
          s.initial_covariance);
  require(std::isfinite(s.max_covariance) && s.max_covariance >= s.initial_covariance,
          "max_covariance must be at least initial_covariance", s.max_covariance);
  require(std::isfinite(s.excitation_m_per_s) && s.excitation_m_per_s >= 0, "excitation_m_per_s must be >= 0",
          s.excitation_m_per_s);
  require(s.min_updates >= 0, "min_updates must be >= 0", s.min_updates);
  require(std::isfinite(s.min_span_m) && s.min_span_m >= 0, "min_span_m must be >= 0", s.min_span_m);
}

ContactIdentifier::ContactIdentifier(const IdentificationSettings& settings) : settings_(settings) { check(settings_); }

void ContactIdentifier::update(const Eigen::Vector3d& position, const Eigen::Vector3d& velocity,
                               const Eigen::Vector3d& normal, const Eigen::Vector3d& force, bool in_contact) noexcept {
  if (!settings_.enabled) return;
  if (!in_contact) {
    touching_ = false;
    return;
  }
  if (!position.allFinite() || !velocity.allFinite() || !force.allFinite() || !normal.allFinite()) return;
  if (!touching_) {  // a new contact: its depth origin here, nothing learnt yet
    touching_ = true;
    valid_ = false;
    touch_ = position;
    theta_.setZero();
    p_ = settings_.initial_covariance * Eigen::Matrix3d::Identity();
    updates_ = 0;
    min_depth_mm_ = max_depth_mm_ = 0;
  }
  const double rate = -normal.dot(velocity);
  if (std::abs(rate) < settings_.excitation_m_per_s) return;
  const double depth_mm = kMm * normal.dot(touch_ - position);
  const Eigen::Vector3d phi(depth_mm, kMm * rate, 1.0);
  const double f = normal.dot(force);
  const Eigen::Vector3d pphi = p_ * phi;
  const double lambda = p_.trace() > settings_.max_covariance ? 1.0 : settings_.forgetting;
  const Eigen::Vector3d gain = pphi / (lambda + phi.dot(pphi));
  theta_ += gain * (f - phi.dot(theta_));
  p_ = (p_ - gain * pphi.transpose()) / lambda;
  p_ = 0.5 * (p_ + p_.transpose());  // round-off keeps it symmetric
  ++updates_;
  min_depth_mm_ = std::min(min_depth_mm_, depth_mm);
  max_depth_mm_ = std::max(max_depth_mm_, depth_mm);
  valid_ = updates_ >= settings_.min_updates && max_depth_mm_ - min_depth_mm_ >= kMm * settings_.min_span_m;
}

HuntCrossleyIdentifier::HuntCrossleyIdentifier(const IdentificationSettings& settings, double initial_exponent)
    : settings_(settings) {
  check(settings_);
  if (!(std::isfinite(initial_exponent) && initial_exponent > 0))
    throw std::invalid_argument("identification: the initial Hunt-Crossley exponent must be positive (got " +
                                std::to_string(initial_exponent) + ")");
  theta_ = Eigen::Vector3d(0, 0, initial_exponent);
  p_ = settings_.initial_covariance * Eigen::Matrix3d::Identity();
  p_(2, 2) = 1;  // n is known to lie near 1-2: its prior is tighter than that of the force scales
}

void HuntCrossleyIdentifier::update(double depth_m, double rate_m_per_s, double force_n) noexcept {
  if (!settings_.enabled) return;
  if (!(depth_m > 0 && force_n > 0 && std::isfinite(rate_m_per_s)) || std::abs(rate_m_per_s) < settings_.excitation_m_per_s)
    return;
  const double x = kMm * depth_m, v = kMm * rate_m_per_s;
  const double xn = std::pow(x, theta_(2)), law = theta_(0) + theta_(1) * v;
  const Eigen::Vector3d phi(xn, xn * v, xn * law * std::log(x));
  const Eigen::Vector3d pphi = p_ * phi;
  const double lambda = p_.trace() > settings_.max_covariance ? 1.0 : settings_.forgetting;
  const Eigen::Vector3d gain = pphi / (lambda + phi.dot(pphi));
  theta_ += gain * (force_n - xn * law);
  theta_(2) = std::clamp(theta_(2), 0.5, 4.0);  // a contact law, not a fit to noise
  p_ = (p_ - gain * pphi.transpose()) / lambda;
  p_ = 0.5 * (p_ + p_.transpose());
  ++updates_;
}

// SI: k x^n with x in m equals a (x / 1 mm)^n, so k = a / (1 mm)^n; lambda_hc likewise with v.
double HuntCrossleyIdentifier::stiffness() const { return theta_(0) / std::pow(1e-3, theta_(2)); }
double HuntCrossleyIdentifier::damping() const { return theta_(1) * kMm / std::pow(1e-3, theta_(2)); }

double HuntCrossleyIdentifier::predict_n(double depth_m, double rate_m_per_s) const {
  if (!(depth_m > 0)) return 0;
  const double x = kMm * depth_m, v = kMm * rate_m_per_s;
  return std::pow(x, theta_(2)) * (theta_(0) + theta_(1) * v);
}

}  // namespace fetouch::haptics
