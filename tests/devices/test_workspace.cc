// The workspace mapping, clutch and engage ramp (haptics/workspace.h) against the formulas of its
// header, worked by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "haptics/workspace.h"

namespace fetouch::haptics {
namespace {

DeviceState at(double x, double y, double z, std::uint32_t buttons = 0) {
  DeviceState s;
  s.position_m = Eigen::Vector3d(x, y, z);
  s.velocity_m_per_s = Eigen::Vector3d(0.1, 0, 0);
  s.buttons = buttons;
  return s;
}

TEST(Workspace, MapsTheDeviceFrameIntoTheSceneAndForcesBack) {
  WorkspaceMapping m;
  // Device y up, scene z up: the device's axes in the scene are x -> x, y -> z, z -> -y.
  m.rotation << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  m.scale = 2;
  m.offset_m = Eigen::Vector3d(0.1, 0.2, 0.3);
  m.ramp_s = 0;
  Workspace w(m, 1e-3);
  const DeviceState s = w.to_scene(at(0.01, 0.02, 0.03));
  // x_s = 2 R x_d + o = 2 (0.01, -0.03, 0.02) + o.
  EXPECT_NEAR(s.position_m.x(), 0.12, 1e-15);
  EXPECT_NEAR(s.position_m.y(), 0.14, 1e-15);
  EXPECT_NEAR(s.position_m.z(), 0.34, 1e-15);
  EXPECT_NEAR(s.velocity_m_per_s.x(), 0.2, 1e-15);
  // A force up in the scene (+z) is +y on the device.
  Eigen::Vector3d sent;
  const Eigen::Vector3d f = w.to_device(Eigen::Vector3d(0, 0, 1.5), sent);
  EXPECT_NEAR(f.y(), 1.5, 1e-15);
  EXPECT_NEAR(f.x(), 0, 1e-15);
  EXPECT_NEAR(f.z(), 0, 1e-15);
  EXPECT_EQ(sent, Eigen::Vector3d(0, 0, 1.5));
}

TEST(Workspace, RampsTheForceInAtEngage) {
  WorkspaceMapping m;
  m.engage_button = 0;
  m.ramp_s = 0.5;
  Workspace w(m, 1e-3);
  Eigen::Vector3d sent;
  for (int k = 0; k < 10; ++k) {  // not engaged: no force
    w.to_scene(at(0, 0, 0));
    EXPECT_EQ(w.to_device(Eigen::Vector3d(0, 0, 2), sent).norm(), 0);
  }
  for (int k = 0; k <= 600; ++k) {
    w.to_scene(at(0, 0, 0, k < 5 ? 1u : 0u));  // pressed briefly: engaged for good
    w.to_device(Eigen::Vector3d(0, 0, 2), sent);
    // g = k / 500 ticks (0.5 s at 1 kHz), then 1.
    EXPECT_NEAR(sent.z(), 2 * std::min(1.0, k / 500.0), 1e-12) << k;
  }
  EXPECT_TRUE(w.engaged());
}

TEST(Workspace, ClutchRecentresWithoutMovingTheProbe) {
  WorkspaceMapping m;
  m.clutch_button = 1;
  m.ramp_s = 0.1;
  Workspace w(m, 1e-3);
  EXPECT_NEAR(w.to_scene(at(0.05, 0, 0)).position_m.x(), 0.05, 1e-15);
  // Clutch held while the hand goes back 4 cm: the probe stays at 5 cm, no force.
  Eigen::Vector3d sent;
  for (int k = 0; k <= 40; ++k) {
    const DeviceState s = w.to_scene(at(0.05 - 0.001 * k, 0, 0, 2u));
    EXPECT_NEAR(s.position_m.x(), 0.05, 1e-15);
    EXPECT_EQ(w.to_device(Eigen::Vector3d(1, 0, 0), sent).norm(), 0);
  }
  // Released at 1 cm: the probe goes on from 5 cm, so 1 cm more on the device is 6 cm in the scene.
  EXPECT_NEAR(w.to_scene(at(0.01, 0, 0)).position_m.x(), 0.05, 1e-15);
  EXPECT_NEAR(w.to_scene(at(0.02, 0, 0)).position_m.x(), 0.06, 1e-15);
  EXPECT_NEAR(w.clutch_shift().x(), 0.04, 1e-15);
  // and the force ramps in again over 0.1 s.
  w.to_device(Eigen::Vector3d(1, 0, 0), sent);
  EXPECT_LT(sent.x(), 0.05);
}

TEST(Workspace, RefusesWhatIsNotARotationOrButtonsThatClash) {
  WorkspaceMapping m;
  m.rotation(0, 0) = -1;  // a reflection
  EXPECT_THROW(Workspace(m, 1e-3), std::invalid_argument);
  WorkspaceMapping n;
  n.engage_button = n.clutch_button = 2;
  EXPECT_THROW(Workspace(n, 1e-3), std::invalid_argument);
  WorkspaceMapping s;
  s.scale = 0;
  EXPECT_THROW(Workspace(s, 1e-3), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::haptics
