// How thick a segmentation is: twice the radius of the largest ball inside it, from a chamfer
// distance transform (each voxel's distance to the nearest voxel outside, through the 26
// neighbours at their true lengths; exact along axes and diagonals, within 8 % elsewhere).
#pragma once

#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

// Millimetres: a sheet one voxel thick gives the voxel's size, a slab of three voxels three.
// 0 for an empty mask.
double thickest_part_mm(const MaskVolume& mask);

}  // namespace fetouch::meshes
