// Contact geometry in 3D. The environment describes the tissue's surface near each contact by a
// contact frame: a surface point x, the outward unit normal n and, optionally, the local quadric
// (second fundamental form) C in the tangent basis T = [t1 t2] of n:
//
//     surface near x:   s(u) = x + T u + n h(u),   h(u) = -1/2 u' C u,   u in R^2
//
// (C = I / R for a sphere of radius R seen from outside; C = 0 for a plane). For a device point p,
// with u = T'(p - x) and its height d = n.(p - x) above the tangent plane:
//
//     penetration        e = h(u) - d            (> 0: the device is inside the tissue)
//     surface point      s(u), directly below (or above) the device along n: the proxy in contact
//
// The force rendered on the device is F n with F >= 0 (contact pushes, never pulls); the tissue
// receives -F n. Everything here is allocation-free and noexcept.
#pragma once

#include <Eigen/Core>

namespace fetouch::haptics {

struct ContactFrame {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Matrix2d curvature = Eigen::Matrix2d::Zero();  // C; zero: the tangent plane
};

// A right-handed orthonormal tangent basis [t1 t2] of the unit normal n (t1 x t2 = n). It depends
// on n only, so the environment and the haptic side agree on what C's coordinates mean.
Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& normal) noexcept;

struct ContactPoint {
  double penetration = 0;                                 // e
  Eigen::Vector3d surface_point = Eigen::Vector3d::Zero();  // s(u) under the device
};

ContactPoint locate(const ContactFrame& frame, const Eigen::Vector3d& device) noexcept;

// The FOH of a frame: points, normals and curvatures interpolated linearly, the normal
// renormalised (t in [0, 1]; t = 1 gives `newest`).
void interpolate(const ContactFrame& previous, const ContactFrame& newest, double t, ContactFrame& out) noexcept;

}  // namespace fetouch::haptics
