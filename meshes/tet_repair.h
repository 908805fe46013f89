// Tetrahedral mesh geometry, quality and sliver repair, independent of any mesher.
//
// A mesher that must keep a given surface (Gmsh inside a segmented surface) leaves slivers where
// it may not move the surface's nodes: flat tetrahedra whose four nodes lie nearly in a plane.
// repair_slivers removes them by local operations that each keep the mesh valid (every element
// positively oriented, the boundary closed and manifold) and that are applied only when they raise
// the worst dihedral angle of the elements they touch:
//   - peeling: a sliver with two or three faces on the boundary is cut away (the boundary then
//     runs along its other faces; the volume lost is the sliver's, which is nearly nothing);
//   - flips: 2-3 (two elements sharing an interior face become three around a new edge) and 3-2
//     (three elements around an interior edge become two); with regions also 4-4 (four around an
//     edge become four around a diagonal of their ring) and edge removal (rings of 5 to 7 around
//     an edge retriangulated without it, the best triangulation of the ring found by dynamic
//     programming);
//   - with regions, a flat cap on an interface (two of its faces on it, folded by under 30 degrees)
//     changes sides when a flip in the region across then removes it (the interface takes its other
//     two faces: an edge flip of the interface);
//   - relocation: an interior node of a sliver moves towards where its elements would be
//     regular, if the worst angle around it improves.
#pragma once

#include <array>
#include <vector>

namespace fetouch::meshes {

using Point3 = std::array<double, 3>;
using Tet = std::array<int, 4>;
using Triangle = std::array<int, 3>;

// The face opposite vertex f, ordered so that its normal (1 - 0) x (2 - 0) points out of a
// positively oriented element.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

double tet_signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

// The six dihedral angles (degrees) of a positively oriented tetrahedron.
std::array<double, 6> dihedral_angles_deg(const Point3& a, const Point3& b, const Point3& c, const Point3& d);

// The smallest dihedral angle, or 0 for an element that is not positively oriented.
double min_dihedral_deg(const std::vector<Point3>& nodes, const Tet& t);

// The faces that belong to exactly one element, oriented outwards.
std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets);

// True when every face belongs to one or two elements and the boundary faces form a closed
// 2-manifold: each boundary edge in exactly two boundary faces, each boundary node's faces one fan.
bool boundary_is_closed_manifold(const std::vector<Tet>& tets);

// Both at once (one pass over the faces).
std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets, bool* closed_manifold);

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

// Moves the boundary nodes along their (area-weighted) normals by one offset so that the mesh
// encloses `target_volume` (a surface remeshed by chords, or contoured from a blurred mask, lies a
// little inside a convex shape; a few tenths of a millimetre over a whole uterus is 3 % of its
// wall). The offset is at most `max_offset` either way; none is applied if it would turn an element
// over or flatten one below `floor_deg` where it was above. Returns the offset applied (0:
// none), in the nodes' unit.
double restore_volume(std::vector<Point3>& nodes, const std::vector<Tet>& tets, double target_volume, double max_offset,
                      double floor_deg);

struct SliverRepair {
  int peeled = 0, flips23 = 0, flips32 = 0, flips44 = 0, relocated = 0;
  int edge_removals = 0;  // rings of 5 to 7 elements around an edge retriangulated without it
  int caps_moved = 0;  // flat elements on an interface moved to its other side (then flipped away)
  double peeled_volume = 0;  // the volume cut away by peeling
  double min_dihedral_before_deg = 0, min_dihedral_after_deg = 0;
};

// Improves every element whose smallest dihedral angle is under `target_deg`, as far as the
// operations above allow; nodes no element uses any more are removed (indices renumbered). With
// `region` (each element's), the faces between regions are kept as the boundary is: no flip crosses
// them, their nodes move only along them where they are flat, and nothing is peeled off them; the
// regions follow the elements.
SliverRepair repair_slivers(std::vector<Point3>& nodes, std::vector<Tet>& tets, double target_deg,
                            std::vector<int>* region = nullptr);

}  // namespace fetouch::meshes
