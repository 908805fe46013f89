// The surface of a segmentation sampled by CGAL's Delaunay refinement (Mesh_3's surface criteria:
// Boissonnat and Oudot's restricted Delaunay surface): the mask is blurred a little, and its 0.5
// level is sampled until every surface triangle has angles of at least 25 degrees, a circumradius
// under the size, and its circumcentre within a distance of the level. The triangles are facets of
// one 3D Delaunay triangulation, so they never cross one another, and CGAL's manifold criterion
// refines until every edge has two triangles and every node one fan of them: whatever the
// threshold left (folds, thin sheets, branches), the surface handed to the volume mesher is closed,
// manifold and free of self-intersections, and features thinner than the elements are either
// resolved by smaller triangles (the distance bound) or left out.
#pragma once

#include <vector>

#include "meshes/tet_repair.h"
#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

struct RestrictedSurface {
  std::vector<Point3> nodes_mm;     // in space (the mask's origin and direction cosines)
  std::vector<Triangle> triangles;  // facing out
  int pieces = 0;                   // connected pieces of the segmentation CGAL seeded
  double seconds = 0;
};

// Triangles of about `s.element_size_mm` where the surface is smooth (`s.refine_size_mm` within
// each of `s.refine_balls`, graded over one more radius), none straying more
// than `distance_mm` from the level. Throws std::runtime_error when nothing of the mask reaches the
// level (empty, or nothing thicker than a voxel).
RestrictedSurface restricted_surface(const MaskVolume& mask, const MeshingSettings& s, double distance_mm);

}  // namespace fetouch::meshes
