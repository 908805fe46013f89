#include "app/study/passivity_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fetouch::app {

namespace {

// The verdict of the stated criterion, bounces counted beyond `ideal_bounces`.
bool oscillates(const Oscillation& o, long ideal_bounces, const OscillationCriterion& c) {
  return o.ringing_s >= c.sustained_s - 1e-9 || o.chatter_ticks >= c.chatter_ticks || o.bounces - ideal_bounces >= c.bounces;
}

}  // namespace

Oscillation detect_oscillation(const std::vector<double>& force, double period_s, double clamp_n,
                               const OscillationCriterion& c) {
  Oscillation out;
  const long n = static_cast<long>(force.size());
  const long half = std::max(1, c.smoothing_ticks / 2);
  const long window = std::max(1L, std::lround(c.window_s / period_s));
  // A running sum gives the centred moving average in one pass.
  std::vector<double> prefix(static_cast<std::size_t>(n) + 1, 0.0);
  for (long k = 0; k < n; ++k) prefix[static_cast<std::size_t>(k) + 1] = prefix[static_cast<std::size_t>(k)] + force[static_cast<std::size_t>(k)];
  // Each window's swing; then the longest stretch of ringing windows whose last window swings at
  // least decay_share of its first (from any window on: a big transient before a steady ring does
  // not hide the ring).
  std::vector<double> swing;
  for (long start = half; start + window <= n - half; start += window) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    int sign = 0, crossings = 0;  // sign changes of what is left, beyond a quarter of ringing_n
    for (long k = start; k < start + window; ++k) {
      const double mean = (prefix[static_cast<std::size_t>(k + half + 1)] - prefix[static_cast<std::size_t>(k - half)]) / (2 * half + 1);
      const double rest = force[static_cast<std::size_t>(k)] - mean;
      lo = std::min(lo, rest), hi = std::max(hi, rest);
      const int now = rest > 0.25 * c.ringing_n ? 1 : rest < -0.25 * c.ringing_n ? -1 : 0;
      if (now != 0 && now != sign) crossings += sign != 0, sign = now;
    }
    out.ringing_ptp_n = std::max(out.ringing_ptp_n, hi - lo);
    // A frame's step (a zero-order hold's staircase) swings once; a ring goes back and forth.
    swing.push_back(crossings >= c.ringing_crossings ? hi - lo : 0.0);
  }
  long longest = 0;
  for (std::size_t a = 0; a < swing.size(); ++a) {
    if (!(swing[a] > c.ringing_n)) continue;
    for (std::size_t b = a; b < swing.size() && swing[b] > c.ringing_n; ++b)
      if (swing[b] >= c.decay_share * swing[a]) longest = std::max(longest, static_cast<long>(b - a + 1));
  }
  out.ringing_s = static_cast<double>(longest * window) * period_s;
  for (long k = 0; k < n; ++k) {
    if (!(force[static_cast<std::size_t>(k)] >= 0.99 * clamp_n)) continue;
    for (long j = std::max(0L, k - 5); j <= std::min(n - 1, k + 5); ++j)
      if (force[static_cast<std::size_t>(j)] <= 0.01 * clamp_n) {
        ++out.chatter_ticks;
        break;
      }
  }
  // Contacts: runs of ticks with a force over 1 % of the clamp; a bounce is one that begins within
  // bounce_gap_s of the last one's end and reaches bounce_share of the clamp.
  const long gap = std::lround(c.bounce_gap_s / period_s);
  long last_end = -1;
  for (long k = 0; k < n;) {
    if (!(force[static_cast<std::size_t>(k)] > 0.01 * clamp_n)) {
      ++k;
      continue;
    }
    const long begin = k;
    double peak = 0;
    for (; k < n && force[static_cast<std::size_t>(k)] > 0.01 * clamp_n; ++k) peak = std::max(peak, force[static_cast<std::size_t>(k)]);
    if (last_end >= 0 && begin - last_end <= gap && peak >= c.bounce_share * clamp_n) ++out.bounces;
    last_end = k;
  }
  out.oscillates = oscillates(out, 0, c);
  return out;
}

double felt_stiffness(const std::vector<Eigen::Vector3d>& forces, const std::vector<Eigen::Vector3d>& positions) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = std::min(forces.size(), positions.size());
  std::size_t first = n, peak = 0;
  double largest = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double f = forces[k].norm();
    if (f > 0 && first == n) first = k;
    if (f > largest) largest = f, peak = k;
  }
  if (first >= n || !(largest > 0)) return nan;
  const Eigen::Vector3d press = -forces[peak] / largest;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  long count = 0;
  for (std::size_t k = first; k <= peak; ++k) {
    const double f = forces[k].norm();
    if (f < 0.2 * largest || f > 0.8 * largest) continue;
    const double depth = (positions[k] - positions[first]).dot(press);
    sx += depth, sy += f, sxx += depth * depth, sxy += depth * f, ++count;
  }
  if (count < 10) return nan;
  const double var = sxx - sx * sx / count;
  return var > 0 ? (sxy - sx * sy / count) / var : nan;
}

Oscillation judge_against_ideal(Oscillation run, const Oscillation& ideal, const OscillationCriterion& c) {
  run.ideal_bounces = ideal.bounces;
  run.oscillates = oscillates(run, ideal.bounces, c);
  return run;
}

std::optional<IdealWall> wall_at_first_touch(const std::vector<Eigen::Vector3d>& forces,
                                             const std::vector<Eigen::Vector3d>& positions, double stiffness_n_per_m,
                                             double clamp_n) {
  const std::size_t n = std::min(forces.size(), positions.size());
  for (std::size_t k = 0; k < n; ++k) {
    if (!(forces[k].norm() > 0)) continue;
    IdealWall wall;
    wall.point = positions[k > 0 ? k - 1 : 0];
    wall.normal = forces[k].normalized();
    wall.stiffness_n_per_m = stiffness_n_per_m, wall.clamp_n = clamp_n;
    return wall;
  }
  return std::nullopt;
}

std::vector<double> ideal_wall_forces(const haptics::Trajectory& trajectory, const haptics::HandParameters& hand,
                                      const std::vector<haptics::HandEvent>& events, const IdealWall& wall,
                                      double period_s, long max_ticks) {
  if (!(wall.stiffness_n_per_m > 0) || !(wall.clamp_n > 0) || !(period_s > 0))
    throw std::invalid_argument("ideal wall: the stiffness, the clamp and the period must be positive");
  // K T_s / 2 <= 0.1 N s/m, and at least 100 steps a tick.
  const int substeps = static_cast<int>(std::max(100.0, std::ceil(5 * wall.stiffness_n_per_m * period_s)));
  const double step = period_s / substeps;
  haptics::VirtualOperator hand_model(trajectory, hand, step, events);
  // The session's ticks: one a period from the trajectory's first time to its last (resampled()).
  long ticks = (hand_model.ticks() + substeps - 1) / substeps;
  if (max_ticks >= 0) ticks = std::min(ticks, max_ticks);
  const Eigen::Vector3d normal = wall.normal.normalized();
  std::vector<double> forces(static_cast<std::size_t>(std::max(0L, ticks)), 0.0);
  for (long k = 0; k < ticks; ++k) {
    double sum = 0;
    int steps = 0;
    for (; steps < substeps && !hand_model.finished(); ++steps) {
      const haptics::DeviceState state = hand_model.read();
      const double depth = normal.dot(wall.point - state.position_m);
      const double f = depth > 0 ? std::min(wall.stiffness_n_per_m * depth, wall.clamp_n) : 0.0;
      hand_model.write(f * normal);
      sum += f;
    }
    forces[static_cast<std::size_t>(k)] = steps > 0 ? sum / steps : 0.0;
  }
  return forces;
}

}  // namespace fetouch::app
