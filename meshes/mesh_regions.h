// Regions of a mesh made from a label map: `fetouch mesh --regions wall=1 fluid=2 fetus=3,4,5,6`
// meshes the union of the regions' labels once (volume_mesher.h) and gives every tetrahedron the
// region whose labels cover most of it, counted at 35 points spread evenly through it (a tie or no
// hit: the centroid's region, else its nearest labelled voxel); elements two regions share nearly
// evenly are then handed over where that brings both regions' volumes closer to their labels'
// cover. The regions share their interfaces node for node by construction; an interface follows
// element faces, so it is accurate to about an element (the report gives each region's volume
// against its voxels').
#pragma once

#include <string>
#include <vector>

#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

struct MeshRegion {
  std::string name;
  std::vector<int> labels;
};

// "fetus=3,4,5,6" -> {fetus, {3, 4, 5, 6}}. Throws std::invalid_argument naming the text: no '=', an
// empty or unusable name (letters, digits, '_' and '-' only), a label that is not a whole number
// in 1..255.
MeshRegion parse_region(const std::string& text);

// Sets mesh.region_names, mesh.region (per tetrahedron) and mesh.regions (the report). `labels`
// holds label values (not 0/1) on the grid the mesh was made from. Throws std::invalid_argument
// for a label in two regions, std::runtime_error when a region gets no element.
void assign_regions(VolumeMesh& mesh, const MaskVolume& labels, const std::vector<MeshRegion>& regions);

// The report of a mesh whose mesh.region is set (by assign_regions, or by a mesher that makes the
// regions itself): region_names, regions (elements, volume against the voxels', smallest dihedral
// angle, outer triangles), boundary_region, interfaces and interface_regions. Throws
// std::runtime_error when a region has no element.
void report_regions(VolumeMesh& mesh, const MaskVolume& labels, const std::vector<MeshRegion>& regions);

}  // namespace fetouch::meshes
