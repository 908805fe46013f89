// Filling a closed, manifold triangle surface with tetrahedra by Gmsh, along one of several paths
// (meshes/volume_mesher.cc tries them in turn until one gives a valid mesh of the quality asked).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "meshes/tet_repair.h"
#include "meshes/volume_mesher.h"

namespace fetouch::meshes {

// The surface the tetrahedra fill.
enum class FillSurface {
  remeshed,    // the surface split into patches Gmsh parametrises and remeshes at the size
  as_given,    // the surface's own triangles kept
  restricted   // a restricted Delaunay surface (meshes/restricted_surface.h), kept
};
// Gmsh's volume mesher. Its Delaunay mesher gives the same mesh of the same surface in every
// process; HXT does not (it numbers the surface's nodes in the order of their addresses in memory,
// docs/meshing.md), so Delaunay is tried first and HXT where Delaunay misses the angle asked.
enum class FillMesher { delaunay, hxt };
struct FillPath {
  FillSurface surface;
  FillMesher mesher;
};
// Delaunay, then HXT, on one surface.
std::vector<FillPath> fill_paths(FillSurface surface);
const char* describe(FillSurface surface);
std::string describe(FillPath path);

struct GmshFill {
  std::vector<Point3> nodes_m;
  std::vector<Tet> tetrahedra;  // positively oriented
  bool surface_remeshed = false;
  double optimisation_seconds = 0;  // Gmsh's optimisers after the mesh
};

// `nodes_mm`: x, y, z per node; `triangles`: three 0-based node indices each, outward or not.
// Throws std::runtime_error with Gmsh's reason and, where Gmsh names a place (two facets that
// intersect, a point it could not recover), that place in millimetres.
GmshFill gmsh_fill(const std::vector<double>& nodes_mm, const std::vector<std::size_t>& triangles,
                   const MeshingSettings& settings, FillPath path);

}  // namespace fetouch::meshes
