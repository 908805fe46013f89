// What `fetouch study passivity` reads off a run's forces (app/study/passivity_study.cc): whether
// the loop with the hand in it oscillated, and the stiffness the hand felt. Pure functions of the
// force and position series, so tests can check them against signals whose answer is known.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <vector>

#include "haptics/devices.h"

namespace fetouch::app {

// The criterion, stated so that a run either meets it or not:
//   - ringing: the force's magnitude less its centred moving average over `smoothing_ticks` (what
//     is left is its content above about 1 / (smoothing_ticks T): 90 Hz at 11 ticks of 1 ms, far
//     above physiological tremor, 6-12 Hz, and below the rings a sampled wall makes) has a
//     peak-to-peak over `ringing_n` in every window of `window_s` for at least `sustained_s` in a
//     row, changing sign (beyond a quarter of ringing_n) at least `ringing_crossings` times in each
//     (since 2026-11-27: a zero-order hold's frame steps, one jump a 50 ms frame, swing as much
//     but do not go back and forth), and its last window still swings at least `decay_share` of its first: a stable loop's
//     answer to a step (an impact, a grip) dies out (a ring that halves within `sustained_s` is a
//     light hand's own decaying mode, not the loop's);
//   - chatter at the clamp: ticks at 99 % of the device's largest force or more within 5 ticks of
//     one at 1 % or less, at least `chatter_ticks` of them (the force jumping between nothing and
//     everything);
//   - bouncing (since 2026-11-27): a contact that begins again within `bounce_gap_s` of the end of
//     the one before and whose force reaches `bounce_share` of the device's largest force, at least
//     `bounces` times (the hand thrown off the tissue and back, over and over: a slow instability,
//     a few hertz, that neither the ring's high-pass nor the chatter's five ticks see; a trajectory
//     does not poke three times within a quarter second of each release). Bounces are the loop's
//     only beyond those the same hand makes on the ideal tissue (IdealWall below): a light grip
//     with little damping rattles on a hard elastic surface however perfectly it is rendered
//     (measured: the default hand 3 times on the 1 MPa block's ideal wall, a 0.4 kg hand on a 230
//     N/m, 0.5 N s/m grip 61 times), and a loop cannot be asked to do better than the tissue.
struct OscillationCriterion {
  int smoothing_ticks = 11;
  double window_s = 0.05;
  double ringing_n = 0.1;
  int ringing_crossings = 3;
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
  long ideal_bounces = 0;   // those the same hand makes on the ideal tissue (judge_against_ideal)
  bool oscillates = false;
};

// `force`: the force's magnitude per tick (N); `period_s`: T; `clamp_n`: the device's largest force.
Oscillation detect_oscillation(const std::vector<double>& force, double period_s, double clamp_n,
                               const OscillationCriterion& criterion = {});

// The run judged against the ideal tissue: ringing and chatter as detect_oscillation says, bouncing
// only when the run bounces at least `criterion.bounces` times more than `ideal` (the same hand
// and events on the IdealWall, judged by detect_oscillation).
Oscillation judge_against_ideal(Oscillation run, const Oscillation& ideal, const OscillationCriterion& criterion = {});

// The ideal tissue: what a perfect rendering would give the same hand. A flat, elastic, unilateral
// wall (force K d along its outward normal at depth d behind it, nothing in front), through a device
// that clamps at its largest force, in continuous time: the hand (haptics::VirtualOperator, exact
// over each step) and the wall are stepped `substeps` times a tick, enough that the sampled wall's
// own energy leak, K T / 2 per step (Colgate), stays under 0.1 N s/m. The wall of a run is placed
// where its device first touched the tissue, facing the force there, with the stiffest frame's
// condensed stiffness (app/study/passivity_study.cc).
struct IdealWall {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // out of the tissue, unit
  double stiffness_n_per_m = 0, clamp_n = 0;
};

// The ideal wall of a device from its run: through the last point before the force first rose
// (the point itself at the first tick), facing the force there. std::nullopt when it never touched.
std::optional<IdealWall> wall_at_first_touch(const std::vector<Eigen::Vector3d>& forces,
                                             const std::vector<Eigen::Vector3d>& positions, double stiffness_n_per_m,
                                             double clamp_n);

// The force's magnitude per tick of `period_s` (its mean over the tick) while the hand follows
// `trajectory` with `events` against `wall`, for the ticks the session would run (max_ticks < 0:
// the whole trajectory). Throws std::invalid_argument for a wall without stiffness or clamp.
std::vector<double> ideal_wall_forces(const haptics::Trajectory& trajectory, const haptics::HandParameters& hand,
                                      const std::vector<haptics::HandEvent>& events, const IdealWall& wall,
                                      double period_s, long max_ticks = -1);

// The stiffness the hand felt as it pressed in (N/m): the least-squares slope of the force's
// magnitude against the device's depth along the press (the direction opposite to the force at its
// largest, depth 0 where the contact began), over the ticks of the first loading whose force lies
// between 20 % and 80 % of that largest force. NaN when fewer than 10 ticks qualify.
double felt_stiffness(const std::vector<Eigen::Vector3d>& forces, const std::vector<Eigen::Vector3d>& positions);

}  // namespace fetouch::app
