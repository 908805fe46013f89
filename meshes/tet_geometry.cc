// Tetrahedral geometry and quality (meshes/tet_geometry.h).
#include "meshes/tet_geometry.h"

#include <algorithm>
#include <cmath>

namespace fetouch::meshes {

using namespace tet_math;
namespace {
constexpr auto& kFace = kTetFace;
}  // namespace

std::array<Point3, 4> unit_outward_normals(const std::array<Point3, 4>& p) {
  std::array<Point3, 4> n{};
  for (int f = 0; f < 4; ++f) {
    n[f] = cross(sub(p[kFace[f][1]], p[kFace[f][0]]), sub(p[kFace[f][2]], p[kFace[f][0]]));
    const double length = norm(n[f]);
    for (double& x : n[f]) x /= length;
  }
  return n;
}

double tet_signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  return dot(sub(b, a), cross(sub(c, a), sub(d, a))) / 6;
}

std::array<double, 6> dihedral_angles_deg(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  // The dihedral angle at the edge shared by faces f and g is pi minus the angle between their
  // outward normals.
  const auto n = unit_outward_normals({a, b, c, d});
  std::array<double, 6> angles{};
  int k = 0;
  for (int f = 0; f < 4; ++f)
    for (int g = f + 1; g < 4; ++g) angles[k++] = 180 - std::acos(std::clamp(dot(n[f], n[g]), -1.0, 1.0)) * 180 / M_PI;
  return angles;
}

double min_dihedral_deg(const std::vector<Point3>& nodes, const Tet& t) {
  const Point3 &a = nodes[t[0]], &b = nodes[t[1]], &c = nodes[t[2]], &d = nodes[t[3]];
  if (!(tet_signed_volume(a, b, c, d) > 0)) return 0;
  // The smallest angle is at the pair of faces whose outward normals are least opposed: one arc
  // cosine for the element.
  const auto n = unit_outward_normals({a, b, c, d});
  double least = 1;
  for (int f = 0; f < 4; ++f)
    for (int g = f + 1; g < 4; ++g) least = std::min(least, dot(n[f], n[g]));
  return 180 - std::acos(std::clamp(least, -1.0, 1.0)) * 180 / M_PI;
}

QualityReport mesh_quality(const std::vector<Point3>& nodes, const std::vector<Tet>& tets) {
  QualityReport q;
  q.min_dihedral_deg = 180, q.max_dihedral_deg = 0, q.min_radius_ratio = 1;
  for (const auto& t : tets) {
    const Point3 p[4] = {nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]};
    const double volume = tet_signed_volume(p[0], p[1], p[2], p[3]);
    q.volume_m3 += volume;
    double scale = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) scale = std::max(scale, norm(sub(p[a], p[b])));
    if (volume <= 0) {
      ++(std::abs(volume) <= 1e-12 * scale * scale * scale ? q.degenerate : q.inverted);
      q.min_dihedral_deg = 0, q.min_radius_ratio = 0;
      continue;
    }
    double area = 0;
    for (const auto& f : kFace) area += norm(cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]]))) / 2;
    for (double angle : dihedral_angles_deg(p[0], p[1], p[2], p[3])) {
      q.min_dihedral_deg = std::min(q.min_dihedral_deg, angle);
      q.max_dihedral_deg = std::max(q.max_dihedral_deg, angle);
      ++q.dihedral_histogram[std::min(17, static_cast<int>(angle / 10))];
    }
    // Radius ratio 3 r / R: r = 3V / area; R from the products of opposite edges' lengths.
    const double a = norm(sub(p[0], p[1])) * norm(sub(p[2], p[3])), b = norm(sub(p[0], p[2])) * norm(sub(p[1], p[3])),
                 c = norm(sub(p[0], p[3])) * norm(sub(p[1], p[2]));
    const double circumradius = std::sqrt(std::max(0.0, (a + b + c) * (a + b - c) * (a - b + c) * (-a + b + c))) / (24 * volume);
    const double ratio = 3 * (3 * volume / area) / circumradius;
    q.min_radius_ratio = std::min(q.min_radius_ratio, ratio);
    ++q.radius_ratio_histogram[std::clamp(static_cast<int>(ratio * 10), 0, 9)];
  }
  if (tets.empty()) q.min_dihedral_deg = 0, q.min_radius_ratio = 0;
  return q;
}

}  // namespace fetouch::meshes
