// Multi-material meshing of a label map: every region a subdomain of one Delaunay mesh (CGAL's Mesh_3
// on a labelled domain), so that each interface between two regions, and each region's outer
// surface, is a surface mesh of its own that follows its label boundary, and the tetrahedra on
// either side share its triangles.
//
//   1. Each region's indicator (1 on its labels' voxels, else 0), and the background's, blurred by a
//      Gaussian of `label_smoothing_voxels`; a point belongs to the region whose blurred indicator,
//      interpolated trilinearly, is the largest there (0: outside). The boundary between two
//      regions is then a smooth surface through the voxels' staircase (where two blurred indicators
//      cross), not the staircase itself; CGAL's own weighted labelled images do the same with 8-bit
//      weights (its generator of them needs ITK, which is not in the stack).
//   2. A sizing field on the grid: each region's size (MeshingSettings::region_size_mm, else
//      element_size_mm) inside it, the refinement ball's inside the ball, and elsewhere the smallest
//      of these grown by `grading` millimetres per millimetre of distance (a chamfer sweep), so
//      elements grade smoothly from a fine region or ball into the coarse ones around it.
//   3. Delaunay refinement (Boissonnat and Oudot's surface criteria: triangles of at least 25
//      degrees, circumradius under the size, circumcentre within 3 % of the size of the surface,
//      between a twentieth of a voxel and `surface_distance_mm`; cells of radius-edge ratio under 3),
//      every connected piece of every region seeded. Three meshes: the first finds the curves where
//      three regions meet (the background counted), which the others keep as features (chained and
//      smoothed); the second measures each region's volume and area, from which each region's
//      indicator gets a bias that gives it its voxels' volume; the third is kept. Then five Lloyd
//      iterations, sliver perturbation and exudation (bound 15 degrees) and the region-aware
//      sliver repair (meshes/tet_repair.h).
//   4. Each cell takes the region of its subdomain; the faces between regions are the interfaces
//      (VolumeMesh::interfaces), the faces on the background the boundary; the report gives every
//      surface's smoothness and distance to its labels (meshes/interface_quality.h).
// Sequential and seeded: the same label map and settings give the same mesh every run.
#pragma once

#include <vector>

#include "meshes/mesh_regions.h"
#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

// Throws std::invalid_argument for no region, a label in two regions, a size that is not positive;
// std::runtime_error when no region has a voxel, a region gets no element (too small for its
// size), or the estimate passes 20 million elements.
VolumeMesh mesh_labels(const MaskVolume& labels, const std::vector<MeshRegion>& regions, const MeshingSettings& s);

}  // namespace fetouch::meshes
