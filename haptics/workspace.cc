#include "haptics/workspace.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace fetouch::haptics {

Workspace::Workspace(const WorkspaceMapping& mapping, double period_s)
    : mapping_(mapping), ramp_ticks_(std::max<long>(1, std::lround(mapping.ramp_s / period_s))),
      engaged_(mapping.engage_button < 0) {
  const Eigen::Matrix3d& r = mapping.rotation;
  if (!r.allFinite() || (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
      std::abs(r.determinant() - 1) > 1e-2)
    throw std::invalid_argument("workspace: the rotation is not a rotation (orthonormal with determinant +1)");
  if (!(mapping.scale > 0) || !std::isfinite(mapping.scale)) throw std::invalid_argument("workspace: the scale must be positive");
  if (!mapping.offset_m.allFinite()) throw std::invalid_argument("workspace: the offset is not finite");
  for (int b : {mapping.engage_button, mapping.clutch_button})
    if (b < -1 || b > 31) throw std::invalid_argument("workspace: a button is -1 (none) or 0 to 31");
  if (mapping.engage_button >= 0 && mapping.engage_button == mapping.clutch_button)
    throw std::invalid_argument("workspace: the engage and clutch buttons must differ");
  if (!(mapping.ramp_s >= 0)) throw std::invalid_argument("workspace: the ramp time must not be negative");
  if (mapping.ramp_s == 0) ramp_ticks_ = 0;
}

DeviceState Workspace::to_scene(const DeviceState& device) noexcept {
  const auto held = [&](int button) { return button >= 0 && (device.buttons >> button) & 1u; };
  if (!engaged_ && held(mapping_.engage_button)) engaged_ = true, ramp_tick_ = 0;
  DeviceState scene;
  scene.buttons = device.buttons;
  const Eigen::Vector3d mapped = mapping_.scale * (mapping_.rotation * device.position_m) + mapping_.offset_m;
  const bool clutch = held(mapping_.clutch_button);
  if (clutch && !clutched_) held_ = mapped + shift_;            // pressed: the probe stays here
  if (!clutch && clutched_) shift_ = held_ - mapped, ramp_tick_ = 0;  // released: go on from here
  clutched_ = clutch;
  if (clutched_) {
    scene.position_m = held_;
    return scene;
  }
  scene.position_m = mapped + shift_;
  scene.velocity_m_per_s = mapping_.scale * (mapping_.rotation * device.velocity_m_per_s);
  return scene;
}

Eigen::Vector3d Workspace::to_device(const Eigen::Vector3d& scene_force, Eigen::Vector3d& sent) noexcept {
  double gain = 0;
  if (engaged_ && !clutched_) {
    gain = ramp_ticks_ == 0 ? 1.0 : std::min(1.0, double(ramp_tick_) / double(ramp_ticks_));
    if (ramp_tick_ < ramp_ticks_) ++ramp_tick_;
  }
  sent = scene_force.allFinite() ? Eigen::Vector3d(gain * scene_force) : Eigen::Vector3d::Zero();
  return mapping_.rotation.transpose() * sent;
}

}  // namespace fetouch::haptics
