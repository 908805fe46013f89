// The last stage before any device write: whatever the local model computed, the force that reaches a
// device is finite, no larger than the device's maximum, changes no faster than a set rate, and fades
// to zero when the environment stops sending updates (a stalled or crashed solver).
//
// Per tick k with period T, requested force r(k) and the time s(k) since the last environment update:
//   g(k)   = 1                                       if s(k) <= t_w
//          = max(0, 1 - (s(k) - t_w) / t_f)          otherwise        (watchdog fade)
//   h(k)   = 1 until ramp_out(R) is asked at tick k0; then max(0, 1 - (k - k0 + 1) / R)
//                                                                     (a stopping session's ramp out)
//   c(k)   = finite(r(k)) ? g(k) h(k) r(k) : 0
//   c(k)   = c(k) * min(1, F_max / |c(k)|)                            (magnitude clamp)
//   F(k)   = F(k-1) + d * min(1, R T / |d|),  d = c(k) - F(k-1)        (rate limit)
// F(k) stays inside the ball of radius F_max, because F(k-1) and c(k) both do and F(k) lies on the
// segment between them.
//
// Real-time safe: no allocation, no locks, no exceptions.
#pragma once

#include <Eigen/Core>

#include <cstdint>

namespace fetouch::haptics {

// f shortened to at most `limit` along its own direction (the clamp of the safety layer).
inline Eigen::Vector3d clamp_magnitude(const Eigen::Vector3d& f, double limit) noexcept {
  const double size = f.norm();
  return size > limit ? Eigen::Vector3d(f * (limit / size)) : f;
}

struct ForceSafetyLimits {
  double max_force_n = 3.3;
  double max_force_rate_n_per_s = 1000;
  double period_s = 1e-3;
  double watchdog_timeout_s = 0.25;  // t_w
  double watchdog_fade_s = 0.1;      // t_f
};

class ForceSafety {
 public:
  explicit ForceSafety(const ForceSafetyLimits& limits);

  // The force to send this tick. `time_since_update_s` is the age of the newest environment update.
  Eigen::Vector3d filter(const Eigen::Vector3d& requested, double time_since_update_s) noexcept;

  void reset() noexcept { last_.setZero(); }
  // Stopping: from the next filter() on, the force fades linearly to zero over `ticks` ticks (at
  // least 1) and stays there; asking again changes nothing. ramped_out(): the fade is over.
  void ramp_out(long ticks) noexcept {
    if (ramp_left_ < 0) ramp_total_ = ramp_left_ = ticks < 1 ? 1 : ticks;
  }
  bool ramping_out() const noexcept { return ramp_left_ >= 0; }
  bool ramped_out() const noexcept { return ramp_left_ == 0; }
  const ForceSafetyLimits& limits() const { return limits_; }

  // Counters for the recording: ticks whose request was not finite, clamped or rate limited,
  // and ticks under the watchdog's fade.
  std::uint64_t non_finite_ticks() const { return non_finite_; }
  std::uint64_t clamped_ticks() const { return clamped_; }
  std::uint64_t rate_limited_ticks() const { return rate_limited_; }
  std::uint64_t watchdog_ticks() const { return watchdog_; }

 private:
  ForceSafetyLimits limits_;
  Eigen::Vector3d last_ = Eigen::Vector3d::Zero();
  long ramp_left_ = -1, ramp_total_ = 1;  // -1: not stopping
  std::uint64_t non_finite_ = 0, clamped_ = 0, rate_limited_ = 0, watchdog_ = 0;
};

}  // namespace fetouch::haptics
