// The expander's hold: what the local model sees of the slow environment at tick i of a frame
// (0 <= i < N), from the two newest environment answers y(j-1) (newest) and y(j-2).
//
//   ZOH:  y_held(jN + i) = y(j-1)
//   FOH:  y_held(jN + i) = y(j-2) + (i / N) (y(j-1) - y(j-2))    (continuous, one frame later)
//
// The same hold applies to the surface x_o and to the force that produced it (the Smith reference).
#pragma once

#include <Eigen/Core>

namespace fetouch::haptics {

enum class HoldKind { zoh, foh };

inline const char* to_string(HoldKind kind) { return kind == HoldKind::foh ? "foh" : "zoh"; }

// The weight of the newest value at tick i of a frame: 1 for ZOH, i / N for FOH.
inline double hold_weight(HoldKind kind, int tick_in_frame, int ratio) noexcept {
  return kind == HoldKind::zoh ? 1.0 : static_cast<double>(tick_in_frame) / static_cast<double>(ratio);
}

// Writes the held value into `out` (no allocation once `out` has the right size).
inline void apply_hold(HoldKind kind, int tick_in_frame, int ratio, const Eigen::VectorXd& newest,
                       const Eigen::VectorXd& previous, Eigen::VectorXd& out) noexcept {
  if (kind == HoldKind::zoh) {
    out = newest;
  } else {
    out = previous + hold_weight(kind, tick_in_frame, ratio) * (newest - previous);
  }
}

}  // namespace fetouch::haptics
