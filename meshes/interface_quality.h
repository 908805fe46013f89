// How smooth a mesh's surfaces are, and how closely they follow the label boundaries they stand for
// (VolumeMesh::SurfaceReport): every interface between two regions and every region's outer surface
// (or the one outer surface of a mesh without regions). Used by the meshers' reports, by
// `fetouch mesh` and `fetouch check`, and by the tests that hold the interfaces smooth.
#pragma once

#include <array>
#include <vector>

#include "meshes/mesh_regions.h"
#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

// The angle (degrees, 0 to 90) between the normal lines of every two triangles of `triangles` that
// share an edge no other triangle of them has; an edge of three or more (a junction) is left out.
std::vector<double> neighbour_normal_angles_deg(const std::vector<Point3>& nodes, const std::vector<std::array<int, 3>>& triangles);

// The reports of `mesh` (regions set by assign_regions, report_regions or the conforming mesher).
// `labels`: the label map the mesh was made from (on which the distances are measured; empty data:
// not measured), `regions` its regions (empty: every non-zero voxel is the tissue).
std::vector<VolumeMesh::SurfaceReport> surface_smoothness(const VolumeMesh& mesh, const MaskVolume& labels,
                                                          const std::vector<MeshRegion>& regions);

}  // namespace fetouch::meshes
