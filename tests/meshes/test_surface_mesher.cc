// Gmsh filling closed triangle surfaces (meshes/volume_mesher.h): a polyhedral sphere meshed with
// its volume kept, a surface with a hole repaired, and surfaces that cannot be meshed refused
// with the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "meshes/volume_mesher.h"

namespace fetouch::meshes {
namespace {

// An icosahedron subdivided `levels` times onto the sphere of radius r (mm).
void icosphere(double r, int levels, std::vector<Point3>& nodes, std::vector<Triangle>& triangles) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  nodes = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
           {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
               {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  const auto project = [r](Point3 p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Point3{r * p[0] / n, r * p[1] / n, r * p[2] / n};
  };
  for (auto& p : nodes) p = project(p);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    const auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      if (auto it = middle.find(key); it != middle.end()) return it->second;
      nodes.push_back(project({(nodes[a][0] + nodes[b][0]) / 2, (nodes[a][1] + nodes[b][1]) / 2,
                               (nodes[a][2] + nodes[b][2]) / 2}));
      return middle[key] = static_cast<int>(nodes.size()) - 1;
    };
    std::vector<Triangle> finer;
    for (const auto& t : triangles) {
      const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      finer.insert(finer.end(), {{t[0], ab, ca}, {t[1], bc, ab}, {t[2], ca, bc}, {ab, bc, ca}});
    }
    triangles = finer;
  }
}

// The volume a closed, outward triangle surface encloses (divergence theorem), mm^3.
double enclosed(const std::vector<Point3>& n, const std::vector<Triangle>& triangles) {
  double v = 0;
  for (const auto& t : triangles) {
    const Point3 &a = n[t[0]], &b = n[t[1]], &c = n[t[2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
  }
  return v;
}

TEST(SurfaceMesher, SphereKeepsItsVolumeAndQuality) {
  std::vector<Point3> nodes;
  std::vector<Triangle> triangles;
  icosphere(20, 4, nodes, triangles);  // 5120 triangles of about 1.4 mm
  const double polyhedron = enclosed(nodes, triangles);
  ASSERT_NEAR(polyhedron, 4 * M_PI / 3 * 8000, 0.01 * 4 * M_PI / 3 * 8000);
  MeshingSettings s;
  s.element_size_mm = 4;
  const VolumeMesh m = mesh_triangle_surface(nodes, triangles, s);
  EXPECT_NEAR(m.segmented_volume_m3, polyhedron * 1e-9, 1e-6 * polyhedron * 1e-9);
  // Remeshed at 4 mm on a 20 mm sphere, the chords cut about (h^2 / 8 R) / R x 3 of the volume: 1.5 %.
  EXPECT_NEAR(m.volume_m3 / m.segmented_volume_m3, 1, 0.03);
  EXPECT_TRUE(m.closed_manifold);
  EXPECT_EQ(m.quality.inverted + m.quality.degenerate, 0);
  EXPECT_GE(m.quality.min_dihedral_deg, 10);
}

TEST(SurfaceMesher, HoleIsFilled) {
  std::vector<Point3> nodes;
  std::vector<Triangle> triangles;
  icosphere(20, 3, nodes, triangles);
  triangles.erase(triangles.begin());  // one triangle missing: three open edges
  MeshingSettings s;
  s.element_size_mm = 5;
  const VolumeMesh m = mesh_triangle_surface(nodes, triangles, s);
  EXPECT_TRUE(m.closed_manifold);
  EXPECT_NEAR(m.volume_m3 * 1e9, 4 * M_PI / 3 * 8000, 0.05 * 4 * M_PI / 3 * 8000);
}

TEST(SurfaceMesher, NonManifoldAndEmptySurfacesAreRefused) {
  // Two closed tetrahedral surfaces sharing one edge: four faces on that edge, which no hole
  // filling repairs.
  const std::vector<Point3> nodes{{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {0, -10, 0}, {0, 0, -10}};
  const std::vector<Triangle> bowtie{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},
                                     {0, 1, 4}, {0, 5, 1}, {0, 4, 5}, {1, 5, 4}};
  MeshingSettings s;
  s.element_size_mm = 2;
  try {
    mesh_triangle_surface(nodes, bowtie, s);
    FAIL() << "a non-manifold surface was meshed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("could not be repaired"), std::string::npos) << e.what();
  }
  EXPECT_THROW(mesh_triangle_surface(nodes, {}, s), std::runtime_error);
  EXPECT_THROW(mesh_triangle_surface(nodes, {{0, 1, 7}}, s), std::runtime_error);
  s.element_size_mm = 0.001;  // 10 mm tetrahedra in 1 um elements: far beyond the memory
  EXPECT_THROW(mesh_triangle_surface(nodes, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, s), std::runtime_error);
}

}  // namespace
}  // namespace fetouch::meshes

namespace fetouch::meshes {
namespace {

TEST(MaskMesher, DirectionCosinesPlaceTheMeshInSpace) {
  // A 30 x 10 x 10 mm block of voxels whose index axis 0 points along y and axis 1 along -x
  // (a quarter turn about z): the mesh must be long in y, and lie on the side the turn says.
  MaskVolume mask;
  mask.dimensions = {40, 20, 20};
  mask.spacing_mm = {1, 1, 1};
  mask.origin_mm = {100, 0, 0};
  mask.direction = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  mask.data.assign(40 * 20 * 20, 0);
  for (int k = 5; k < 15; ++k)
    for (int j = 5; j < 15; ++j)
      for (int i = 5; i < 35; ++i) mask.data[(std::size_t(k) * 20 + j) * 40 + i] = 1;
  MeshingSettings s;
  s.element_size_mm = 3;
  const VolumeMesh m = mesh_mask(mask, s);
  Point3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
  for (const auto& p : m.nodes_m)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], p[d] * 1e3), hi[d] = std::max(hi[d], p[d] * 1e3);
  // Voxels i = 5..34 span y from 4.5 to 34.5 mm (the surface passes half a voxel out); j = 5..14
  // spans x from 100 - 14.5 to 100 - 4.5. The smoothing rounds the block's edges and lets its
  // faces bulge by about a voxel: 1.5 mm of tolerance (unturned, the block would span 30 mm in x).
  EXPECT_NEAR(lo[1], 4.5, 1.5);
  EXPECT_NEAR(hi[1], 34.5, 1.5);
  EXPECT_NEAR(lo[0], 85.5, 1.5);
  EXPECT_NEAR(hi[0], 95.5, 1.5);
  EXPECT_NEAR(lo[2], 4.5, 1.5);
  EXPECT_NEAR(hi[2], 14.5, 1.5);
  EXPECT_TRUE(m.closed_manifold);
  EXPECT_EQ(m.quality.inverted, 0);
}

}  // namespace
}  // namespace fetouch::meshes
