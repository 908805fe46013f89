#include "app/trainer/deformed_slice.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fetouch::app::trainer {

SlicePlane probe_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& towards,
                       double width_m, double depth_m, int columns, int rows) {
  SlicePlane p;
  p.up = normal.norm() > 0 ? normal.normalized() : Eigen::Vector3d::UnitZ();
  Eigen::Vector3d lateral = towards - towards.dot(p.up) * p.up;
  if (lateral.norm() < 0.1 * towards.norm() || lateral.norm() == 0) {
    lateral = Eigen::Vector3d::UnitX() - p.up.x() * p.up;
    if (lateral.norm() < 0.1) lateral = Eigen::Vector3d::UnitY() - p.up.y() * p.up;
  }
  p.lateral = lateral.normalized();
  p.width_m = width_m, p.height_m = depth_m;
  p.columns = columns, p.rows = rows;
  p.centre = point - 0.5 * depth_m * p.up;
  return p;
}

float ReferenceVolume::sample(const Eigen::Vector3d& x) const {
  if (data.empty()) return outside;
  // Index coordinates: direction^T (x - origin) / spacing (the direction is orthonormal).
  const Eigen::Vector3d local = direction.transpose() * (x - origin_m);
  double f[3];
  int i0[3];
  for (int d = 0; d < 3; ++d) {
    const double c = local[d] / spacing_m[d];
    if (!(c >= 0) || c > dimensions[d] - 1) return outside;
    i0[d] = std::min(static_cast<int>(c), std::max(0, dimensions[d] - 2));
    f[d] = c - i0[d];
  }
  const auto at = [this](int i, int j, int k) {
    i = std::min(i, dimensions[0] - 1), j = std::min(j, dimensions[1] - 1), k = std::min(k, dimensions[2] - 1);
    return static_cast<double>(data[(std::size_t(k) * dimensions[1] + j) * dimensions[0] + i]);
  };
  double value = 0;
  for (int c = 0; c < 8; ++c) {
    const int a = c & 1, b = (c >> 1) & 1, z = (c >> 2) & 1;
    const double w = (a ? f[0] : 1 - f[0]) * (b ? f[1] : 1 - f[1]) * (z ? f[2] : 1 - f[2]);
    if (w != 0) value += w * at(i0[0] + a, i0[1] + b, i0[2] + z);
  }
  return static_cast<float>(value);
}

DeformedSlicer::DeformedSlicer(std::vector<std::array<double, 3>> points, std::vector<std::array<unsigned int, 4>> tetrahedra,
                               std::vector<unsigned int> material)
    : tetrahedra_(std::move(tetrahedra)), material_(std::move(material)) {
  if (material_.size() != tetrahedra_.size()) throw std::invalid_argument("slicer: one region per tetrahedron");
  points_.reserve(points.size());
  for (const auto& p : points) points_.emplace_back(p[0], p[1], p[2]);
  for (const auto& t : tetrahedra_)
    for (unsigned int v : t)
      if (v >= points_.size()) throw std::invalid_argument("slicer: a tetrahedron names a point the mesh does not have");
  deformed_ = points_;
}

void DeformedSlicer::slice(const std::vector<float>& displacement, const SlicePlane& plane, const ReferenceVolume* volume,
                           double gain, std::vector<std::uint8_t>& image, std::vector<float>& reference) {
  const std::size_t pixels = std::size_t(plane.columns) * std::size_t(plane.rows);
  image.resize(pixels);
  reference.assign(3 * pixels, std::numeric_limits<float>::quiet_NaN());
  covering_.assign(pixels, 0);
  const bool moved = displacement.size() == 3 * points_.size();
  for (std::size_t i = 0; i < points_.size(); ++i)
    deformed_[i] = moved ? Eigen::Vector3d(points_[i] + Eigen::Vector3d(displacement[3 * i], displacement[3 * i + 1], displacement[3 * i + 2]))
                         : points_[i];
  const Eigen::Vector3d normal = plane.lateral.cross(plane.up);
  const double pixel_a = plane.width_m / plane.columns, pixel_b = plane.height_m / plane.rows;
  for (std::size_t t = 0; t < tetrahedra_.size(); ++t) {
    const auto& tet = tetrahedra_[t];
    double d[4];
    double dmin = 1e300, dmax = -1e300;
    for (int k = 0; k < 4; ++k) {
      d[k] = (deformed_[tet[k]] - plane.centre).dot(normal);
      dmin = std::min(dmin, d[k]), dmax = std::max(dmax, d[k]);
    }
    if (dmin > 0 || dmax < 0) continue;
    // The pixels to test: those in the box of the tetrahedron's cross-section with the plane (its
    // vertices in the plane and its edges' crossings), a fraction of the box of its projection.
    double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
    const auto extend = [&](const Eigen::Vector3d& x) {
      const Eigen::Vector3d r = x - plane.centre;
      const double a = r.dot(plane.lateral), b = r.dot(plane.up);
      amin = std::min(amin, a), amax = std::max(amax, a), bmin = std::min(bmin, b), bmax = std::max(bmax, b);
    };
    for (int k = 0; k < 4; ++k) {
      if (d[k] == 0) extend(deformed_[tet[k]]);
      for (int m = k + 1; m < 4; ++m)
        if ((d[k] < 0 && d[m] > 0) || (d[k] > 0 && d[m] < 0))
          extend(deformed_[tet[k]] + d[k] / (d[k] - d[m]) * (deformed_[tet[m]] - deformed_[tet[k]]));
    }
    const int i0 = std::max(0, static_cast<int>(std::ceil(amin / pixel_a + 0.5 * plane.columns - 0.5)));
    const int i1 = std::min(plane.columns - 1, static_cast<int>(std::floor(amax / pixel_a + 0.5 * plane.columns - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil(0.5 * plane.rows - bmax / pixel_b - 0.5)));
    const int j1 = std::min(plane.rows - 1, static_cast<int>(std::floor(0.5 * plane.rows - bmin / pixel_b - 0.5)));
    if (i0 > i1 || j0 > j1) continue;
    const Eigen::Vector3d& x0 = deformed_[tet[0]];
    Eigen::Matrix3d m;
    m << deformed_[tet[1]] - x0, deformed_[tet[2]] - x0, deformed_[tet[3]] - x0;
    const double det = m.determinant();
    if (!(std::abs(det) > 1e-30)) continue;  // a flat tetrahedron covers nothing
    const Eigen::Matrix3d inverse = m.inverse();
    const Eigen::Vector3d& X0 = points_[tet[0]];
    const Eigen::Vector3d e1 = points_[tet[1]] - X0, e2 = points_[tet[2]] - X0, e3 = points_[tet[3]] - X0;
    // Barycentric coordinates are affine in the pixel's indices: a step along a row adds `step`.
    const Eigen::Vector3d step = inverse * (pixel_a * plane.lateral);
    for (int j = j0; j <= j1; ++j) {
      Eigen::Vector3d l = inverse * (plane.pixel(i0, j) - x0);
      for (int i = i0; i <= i1; ++i, l += step) {
        const double tolerance = -1e-9;
        if (l[0] < tolerance || l[1] < tolerance || l[2] < tolerance || 1 - l.sum() < tolerance) continue;
        const std::size_t p = std::size_t(j) * plane.columns + i;
        const Eigen::Vector3d X = X0 + l[0] * e1 + l[1] * e2 + l[2] * e3;
        for (int c = 0; c < 3; ++c) reference[3 * p + c] = static_cast<float>(X[c]);
        covering_[p] = static_cast<int>(material_[t]) + 1;
      }
    }
  }
  for (int j = 0; j < plane.rows; ++j)
    for (int i = 0; i < plane.columns; ++i) {
      const std::size_t p = std::size_t(j) * plane.columns + i;
      double value;
      if (volume && !volume->empty()) {
        const Eigen::Vector3d at = covering_[p] ? Eigen::Vector3d(reference[3 * p], reference[3 * p + 1], reference[3 * p + 2])
                                                : plane.pixel(i, j);
        value = gain * volume->sample(at);
      } else {
        // The cross-section: each region its own grey, outside black.
        value = covering_[p] ? 90.0 + 40.0 * ((covering_[p] - 1) % 5) : 0.0;
      }
      image[p] = static_cast<std::uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
}

}  // namespace fetouch::app::trainer
