#include "haptics/contact_frame.h"

#include <Eigen/Geometry>

#include <cmath>

namespace fetouch::haptics {

Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& n) noexcept {
  // The coordinate axis least aligned with n, made orthogonal to it.
  Eigen::Vector3d helper = std::abs(n.x()) < 0.6 ? Eigen::Vector3d::UnitX()
                           : std::abs(n.y()) < 0.6 ? Eigen::Vector3d::UnitY()
                                                   : Eigen::Vector3d::UnitZ();
  Eigen::Vector3d t1 = helper - helper.dot(n) * n;
  t1.normalize();
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = t1;
  basis.col(1) = n.cross(t1);
  return basis;
}

ContactPoint locate(const ContactFrame& frame, const Eigen::Vector3d& device) noexcept {
  ContactPoint c;
  if (frame.curvature.isZero(0)) {  // a plane: h = 0, s(u) is the device moved onto it along n
    c.penetration = -frame.normal.dot(device - frame.point);
    c.surface_point = device + c.penetration * frame.normal;
    return c;
  }
  const Eigen::Matrix<double, 3, 2> tangents = tangent_basis(frame.normal);
  const Eigen::Vector3d offset = device - frame.point;
  const Eigen::Vector2d u = tangents.transpose() * offset;
  const double height = -0.5 * u.dot(frame.curvature * u);
  c.penetration = height - frame.normal.dot(offset);
  c.surface_point = frame.point + tangents * u + height * frame.normal;
  return c;
}

void interpolate(const ContactFrame& previous, const ContactFrame& newest, double t, ContactFrame& out) noexcept {
  out.point = previous.point + t * (newest.point - previous.point);
  out.normal = previous.normal + t * (newest.normal - previous.normal);
  const double length = out.normal.norm();
  out.normal = length > 1e-12 ? Eigen::Vector3d(out.normal / length) : newest.normal;
  out.curvature = previous.curvature + t * (newest.curvature - previous.curvature);
}

}  // namespace fetouch::haptics
