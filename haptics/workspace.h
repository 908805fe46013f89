// A hardware device's workspace in the scene (docs/devices.md): the device frame mapped to the scene
// frame, a button to engage and one to clutch, and the force ramped in at engage.
//
//   x_scene = s R x_device + o + c        v_scene = s R v_device
//   F_device = g R^T F_scene
//
// R a rotation, s a scale (scene metres per device metre: a desk workspace reaching a whole uterus),
// o an offset, c the clutch's shift (zero until the first clutch), g the force gain. While the clutch
// button is held the probe stays where it was in the scene and no force is sent; when it is released
// c is set so the probe goes on from there (re-centring the hand without moving the probe). Until the
// engage button is first pressed (when there is one) no force is sent. After engage and after each
// clutch release, g ramps from 0 to 1 over ramp_s; otherwise g = 1.
//
// Real-time safe: no allocation, locks, exceptions or waits.
#pragma once

#include <Eigen/Core>

#include "haptics/device.h"

namespace fetouch::haptics {

struct WorkspaceMapping {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // device axes in the scene frame
  double scale = 1;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  int engage_button = -1;  // the button (0-based) that engages; -1: engaged from the start
  int clutch_button = -1;  // the button that clutches while held; -1: no clutch
  double ramp_s = 0.5;     // the force's ramp in at engage and after a clutch
};

class Workspace {
 public:
  // Throws std::invalid_argument unless R is a rotation (orthonormal to 1e-3, det +1), s > 0, the
  // buttons are -1 or 0..31 and different, and ramp_s >= 0.
  Workspace(const WorkspaceMapping& mapping, double period_s);

  // The device's state (device frame, m and m/s) in the scene frame; reads the buttons.
  DeviceState to_scene(const DeviceState& device) noexcept;
  // The scene-frame force to send, in the device frame; `sent` is what that is in the scene frame.
  Eigen::Vector3d to_device(const Eigen::Vector3d& scene_force, Eigen::Vector3d& sent) noexcept;
  // Starts the ramp again (after the force was off for a force error).
  void restart_ramp() noexcept { ramp_tick_ = 0; }

  bool engaged() const { return engaged_; }
  bool clutched() const { return clutched_; }
  const Eigen::Vector3d& clutch_shift() const { return shift_; }

 private:
  WorkspaceMapping mapping_;
  long ramp_ticks_;
  long ramp_tick_ = 0;
  bool engaged_, clutched_ = false;
  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero(), held_ = Eigen::Vector3d::Zero();
};

}  // namespace fetouch::haptics
