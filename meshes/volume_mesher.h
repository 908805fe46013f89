// From a segmented volume (a 0/1 mask in millimetres) to a tetrahedral simulation mesh (metres):
//   1. surface extraction: the mask, lightly smoothed, contoured at 0.5 by VTK's flying edges;
//   2. clean-up: windowed-sinc smoothing (which does not shrink), the largest connected piece only,
//      quadric decimation towards the target element size; the surface must come out closed and
//      manifold (no boundary or non-manifold edge), else it is refused;
//   3. volume meshing by Gmsh inside that surface (remeshed at the target size where Gmsh can
//      parametrise it), Gmsh's optimisation, then the sliver repair of meshes/tet_repair.h;
//   4. a quality report: dihedral angles and radius ratios (minimum and histogram), inverted and
//      degenerate elements;
//   5. output as Gmsh .msh 4.1 (physical groups `surface` and `tissue`) and VTK .vtu (the
//      fem/vtu_mesh.h convention: boundary triangles with boundary_id, boundary_names), optionally
//      partitioned by METIS through Gmsh.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "meshes/tet_repair.h"

namespace fetouch::meshes {

struct MaskVolume {
  std::array<int, 3> dimensions{0, 0, 0};
  std::array<double, 3> spacing_mm{1, 1, 1};
  std::array<double, 3> origin_mm{0, 0, 0};
  std::array<double, 9> direction{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major; column c: index axis c
  std::vector<std::uint8_t> data;  // 0/1, x fastest
};

// A point of space (mm) in the frame of the volume's grid padded by `pad` voxels on every side (the
// CGAL meshers' image): millimetres along the index axes (the transpose of the direction cosines).
inline std::array<double, 3> padded_grid_point(const MaskVolume& v, const std::array<double, 3>& point_mm, int pad) {
  std::array<double, 3> g{};
  for (std::size_t c = 0; c < 3; ++c) {
    g[c] = pad * v.spacing_mm[c];
    for (std::size_t r = 0; r < 3; ++r) g[c] += v.direction[3 * r + c] * (point_mm[r] - v.origin_mm[r]);
  }
  return g;
}

struct MeshingSettings {
  double element_size_mm = 4;
  int smoothing_iterations = 20;
  int partitions = 0;  // > 1: METIS partitions (Gmsh)
  // The smallest dihedral angle asked of the mesh: the paths of meshes/gmsh_fill.h are tried until
  // one reaches it (VolumeMesh::quality_met says whether one did).
  double min_dihedral_deg = 10;
  // And the smallest radius ratio (3 r / R: 1 regular, 0 flat) asked of every element.
  double min_radius_ratio = 0.1;
  // false: no restricted Delaunay surface; only the surfaces contoured by VTK (remeshed by Gmsh).
  bool restricted_surface = true;
  // Refinement: elements of refine_size_mm within each ball (a probe's working region each), grading
  // to element_size_mm over one more radius; the finest size wins where balls overlap. None: no ball.
  struct RefineBall {
    std::array<double, 3> center_mm{0, 0, 0};
    double radius_mm = 0;
  };
  std::vector<RefineBall> refine_balls;
  double refine_size_mm = 0;
  // The conforming mesher of a label map (meshes/labeled_mesher.h): each region's size (by region
  // index; absent or 0: element_size_mm), how fast sizes may grow away from a finer region or the
  // refinement ball (mm per mm), the Gaussian that smooths the label boundaries (voxels), and how far
  // at most a surface triangle's circumcentre may stray from its surface (0: half a voxel; less
  // where the elements are small: 4 % of their size, at least a tenth of a voxel).
  std::vector<double> region_size_mm;
  double grading = 0.3;
  double label_smoothing_voxels = 1.0;
  double surface_distance_mm = 0;
  // Progress of the long steps: (step name, fraction of the whole done).
  std::function<void(const std::string&, double)> progress;
};

struct VolumeMesh {
  std::vector<std::array<double, 3>> nodes_m;
  std::vector<std::array<int, 4>> tetrahedra;  // positively oriented
  std::vector<std::array<int, 3>> boundary;    // surface triangles, outward
  QualityReport quality;
  double volume_m3 = 0;
  double segmented_volume_m3 = 0;  // voxels x voxel volume
  long surface_triangles = 0;
  bool closed_manifold = false;
  bool surface_remeshed = false;  // Gmsh parametrised and remeshed the surface (else kept as decimated)
  SliverRepair repair;            // what the sliver repair did after Gmsh
  double surface_offset_mm = 0;   // how far the boundary was moved out to keep the segmented volume
  // How the mesh was made: the path taken (meshes/gmsh_fill.h's describe), each path tried with its
  // outcome, whether the smallest dihedral angle and radius ratio reached MeshingSettings's, and the
  // seconds of each phase ("surface", "volume mesh", "optimisation": Gmsh's optimisers and the
  // sliver repair of the mesh kept).
  std::string path;
  std::vector<std::string> attempts;
  bool quality_met = false;
  std::vector<std::pair<std::string, double>> phases;
  double optimisation_seconds = 0;
  // Regions (mesh_regions.h; empty: one region, `tissue`): names, each tetrahedron's index into
  // them, and per region its elements, volume against its voxels', quality and outer surface.
  struct RegionReport {
    std::string name;
    long tetrahedra = 0, outer_triangles = 0;
    double volume_m3 = 0, voxel_volume_m3 = 0;
    double min_dihedral_deg = 0;
  };
  std::vector<std::string> region_names;
  std::vector<int> region;           // per tetrahedron
  std::vector<int> boundary_region;  // per boundary triangle: its element's region
  std::vector<RegionReport> regions;
  long interface_triangles = 0;  // faces shared by elements of two regions
  // Those faces, each oriented out of its lower region, and the regions on either side (lower
  // index first); written as surface groups named LOWER_HIGHER (`wall_fluid`).
  std::vector<std::array<int, 3>> interfaces;
  std::vector<std::array<int, 2>> interface_regions;
  // How smooth each surface is (meshes/interface_quality.h): every interface (LOWER_HIGHER) and
  // every region's outer surface (REGION_outside), or the one outer surface (`outside`).
  struct SurfaceReport {
    std::string name;
    long triangles = 0;
    // The angle between the normal lines of triangles that share an edge (0 to 90 degrees, their
    // orientation ignored): median, 99th percentile and largest.
    double median_angle_deg = 0, p99_angle_deg = 0, max_angle_deg = 0;
    // The largest distance from the surface (its nodes, edge midpoints and centroids) to the label
    // boundary it stands for (the voxel faces between its two sides); -1 when not measured.
    double max_distance_mm = -1;
  };
  std::vector<SurfaceReport> surfaces;
};

// The interfaces' names in the order their groups are written (by region pair), with their faces.
std::vector<std::pair<std::string, long>> interface_groups(const VolumeMesh& mesh);

// Throws std::runtime_error: an empty mask, a surface that is not closed or not manifold after
// repair, a target size too small for the memory (more than 20 million elements estimated), Gmsh
// failing.
VolumeMesh mesh_mask(const MaskVolume& mask, const MeshingSettings& settings);

// The same from a closed triangle surface in millimetres (its enclosed volume is then the
// reference volume): open edges are filled if they can be; a surface still open or not manifold
// is refused, as is an empty one.
VolumeMesh mesh_triangle_surface(const std::vector<Point3>& nodes_mm, const std::vector<Triangle>& triangles,
                                 const MeshingSettings& settings);

// Writes .msh (4.1) or .vtu by extension; throws std::runtime_error naming the file.
void write_volume_mesh(const VolumeMesh& mesh, const std::filesystem::path& path, int partitions = 0);

}  // namespace fetouch::meshes
