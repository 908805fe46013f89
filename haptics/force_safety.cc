#include "haptics/force_safety.h"

#include <algorithm>
#include <cmath>

namespace fetouch::haptics {

ForceSafety::ForceSafety(const ForceSafetyLimits& limits) : limits_(limits) {}

Eigen::Vector3d ForceSafety::filter(const Eigen::Vector3d& requested,
                                    double time_since_update_s) noexcept {
  Eigen::Vector3d target = requested;
  if (!target.allFinite()) {
    ++non_finite_;
    target.setZero();
  }

  // A NaN age counts as stale: the fade only ever lowers the force.
  if (!(time_since_update_s <= limits_.watchdog_timeout_s)) {
    ++watchdog_;
    const double late = std::isfinite(time_since_update_s)
                            ? time_since_update_s - limits_.watchdog_timeout_s
                            : limits_.watchdog_fade_s;
    const double gain = limits_.watchdog_fade_s > 0
                            ? std::max(0.0, 1.0 - late / limits_.watchdog_fade_s)
                            : 0.0;
    target *= gain;
  }

  if (ramp_left_ >= 0) {
    if (ramp_left_ > 0) --ramp_left_;
    target *= static_cast<double>(ramp_left_) / static_cast<double>(ramp_total_);
  }

  if (target.norm() > limits_.max_force_n) {
    ++clamped_;
    target = clamp_magnitude(target, limits_.max_force_n);
  }

  const Eigen::Vector3d step = target - last_;
  const double max_step = limits_.max_force_rate_n_per_s * limits_.period_s;
  const double step_size = step.norm();
  if (step_size > max_step) {
    ++rate_limited_;
    last_ += step * (max_step / step_size);
  } else {
    last_ = target;
  }
  return last_;
}

}  // namespace fetouch::haptics
