// Tetrahedral geometry and quality, independent of any mesher: signed volumes, dihedral angles,
// each face's outward normal, a mesh's quality report. meshes/tet_repair.h builds on it (boundary
// faces, moving the boundary out to a volume, sliver repair).
#pragma once

#include <array>
#include <cmath>
#include <vector>

namespace fetouch::meshes {

using Point3 = std::array<double, 3>;
using Tet = std::array<int, 4>;
using Triangle = std::array<int, 3>;

// The face opposite vertex f, ordered so that its normal (1 - 0) x (2 - 0) points out of a
// positively oriented element.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Small vector arithmetic on Point3, kept in a namespace of its own so that a file's own helpers of
// the same names do not collide with them.
namespace tet_math {
inline Point3 sub(const Point3& a, const Point3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Point3 cross(const Point3& a, const Point3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const Point3& a) { return std::sqrt(dot(a, a)); }
}  // namespace tet_math

double tet_signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

// The six dihedral angles (degrees) of a positively oriented tetrahedron.
std::array<double, 6> dihedral_angles_deg(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

// The smallest dihedral angle, or 0 for an element that is not positively oriented.
double min_dihedral_deg(const std::vector<Point3>& nodes, const Tet& t);

// The unit outward normal of each face (kTetFace's order) of a positively oriented element.
std::array<Point3, 4> unit_outward_normals(const std::array<Point3, 4>& p);

struct QualityReport {
  double min_dihedral_deg = 0, max_dihedral_deg = 0;
  std::array<long, 18> dihedral_histogram{};      // 10-degree bins, 0..180
  double min_radius_ratio = 0;                // 3 r_inscribed / R_circumscribed: 1 regular, 0 flat
  std::array<long, 10> radius_ratio_histogram{};  // 0.1 bins
  long inverted = 0, degenerate = 0;
  double volume_m3 = 0;  // the sum of the signed volumes
};

// Dihedral angles and radius ratios of every element, inverted and degenerate ones counted.
QualityReport mesh_quality(const std::vector<Point3>& nodes, const std::vector<Tet>& tets);

}  // namespace fetouch::meshes
