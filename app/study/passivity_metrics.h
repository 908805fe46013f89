// What `fetouch study passivity` reads off a run's forces (app/study/passivity_study.cc): whether
// the loop with the hand in it oscillated, and the stiffness the hand felt. Pure functions of the
// force and position series, so tests can check them against signals whose answer is known.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace fetouch::app {

// The criterion, stated so that a run either meets it or not:
//   - ringing: the force's magnitude less its centred moving average over `smoothing_ticks` (what
//     is left is its content above about 1 / (smoothing_ticks T): 90 Hz at 11 ticks of 1 ms, far
//     above physiological tremor, 6-12 Hz, and below the rings a sampled wall makes) has a
//     peak-to-peak over `ringing_n` in every window of `window_s` for at least `sustained_s` in a
//     row, and its last window still swings at least `decay_share` of its first: a stable loop's
//     answer to a step (an impact, a grip) dies out (a ring that halves within `sustained_s` is a
//     light hand's own decaying mode, not the loop's);
//   - chatter at the clamp: ticks at 99 % of the device's largest force or more within 5 ticks of
//     one at 1 % or less, at least `chatter_ticks` of them (the force jumping between nothing and
//     everything);
//   - bouncing (since 2026-11-27): a contact that begins again within `bounce_gap_s` of the end of
//     the one before and whose force reaches `bounce_share` of the device's largest force, at least
//     `bounces` times (the hand thrown off the tissue and back, over and over: a slow instability,
//     a few hertz, that neither the ring's high-pass nor the chatter's five ticks see; a trajectory
//     does not poke three times within a quarter second of each release).
struct OscillationCriterion {
  int smoothing_ticks = 11;
  double window_s = 0.05;
  double ringing_n = 0.1;
  double sustained_s = 0.3;
  double decay_share = 0.5;
  long chatter_ticks = 3;
  double bounce_gap_s = 0.25;
  double bounce_share = 0.1;
  long bounces = 3;
};

struct Oscillation {
  double ringing_s = 0;     // the longest stretch of windows that ring without dying out, s
  double ringing_ptp_n = 0; // the largest high-frequency peak-to-peak in any window, N
  long chatter_ticks = 0;
  long bounces = 0;         // contacts that began again soon after the last and pressed hard
  bool oscillates = false;
};

// `force`: the force's magnitude per tick (N); `period_s`: T; `clamp_n`: the device's largest force.
Oscillation detect_oscillation(const std::vector<double>& force, double period_s, double clamp_n,
                               const OscillationCriterion& criterion = {});

// The stiffness the hand felt as it pressed in (N/m): the least-squares slope of the force's
// magnitude against the device's depth along the press (the direction opposite to the force at its
// largest, depth 0 where the contact began), over the ticks of the first loading whose force lies
// between 20 % and 80 % of that largest force. NaN when fewer than 10 ticks qualify.
double felt_stiffness(const std::vector<Eigen::Vector3d>& forces, const std::vector<Eigen::Vector3d>& positions);

}  // namespace fetouch::app
