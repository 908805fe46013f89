// Tetrahedral mesh boundaries and sliver repair, independent of any mesher (the geometry and the
// quality report: meshes/tet_geometry.h).
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

#include "meshes/tet_geometry.h"

namespace fetouch::meshes {

// The faces that belong to exactly one element, oriented outwards.
std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets);

// True when every face belongs to one or two elements and the boundary faces form a closed
// 2-manifold: each boundary edge in exactly two boundary faces, each boundary node's faces one fan.
bool boundary_is_closed_manifold(const std::vector<Tet>& tets);

// Both at once (one pass over the faces).
std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets, bool* closed_manifold);

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
