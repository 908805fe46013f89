// The conforming mesher of a label map (meshes/labeled_mesher.h) and the surface report
// (meshes/interface_quality.h), against geometry known in closed form: a shell of radius 22 to 30 mm
// around a liquid ball, with a core ball (radius 9 mm) that pushes into the shell, so that three
// regions meet along a circle. Independent answers: the icosahedron's dihedral angle, the spheres'
// radii, the voxels counted here; and the voted path on the same labels, whose interfaces are
// staircases (the report must tell the two apart).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "meshes/interface_quality.h"
#include "meshes/labeled_mesher.h"

namespace fetouch::meshes {
namespace {

constexpr int kN = 72;
constexpr double kCentre = 36, kShellInner = 22, kShellOuter = 30, kCoreRadius = 9, kCoreHeight = 15;

// 1 the shell, 2 the liquid, 3 the core (centred kCoreHeight above the centre, cut by nothing: it
// replaces the shell's voxels where it reaches into it); 1 mm voxels.
MaskVolume three_labels() {
  MaskVolume v;
  v.dimensions = {kN, kN, kN};
  v.data.assign(std::size_t(kN) * kN * kN, 0);
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const double x = i - kCentre, y = j - kCentre, z = k - kCentre;
        const double r = std::sqrt(x * x + y * y + z * z);
        const double c = std::sqrt(x * x + y * y + (z - kCoreHeight) * (z - kCoreHeight));
        std::uint8_t label = r < kShellInner ? 2 : r < kShellOuter ? 1 : 0;
        if (c < kCoreRadius) label = 3;
        v.data[(std::size_t(k) * kN + j) * kN + i] = label;
      }
  return v;
}

const std::vector<MeshRegion> kRegions = {{"shell", {1}}, {"liquid", {2}}, {"core", {3}}};

const VolumeMesh& conforming() {
  static const VolumeMesh mesh = [] {
    MeshingSettings s;
    s.element_size_mm = 4;
    s.region_size_mm = {5, 0, 2.5};  // the core finer, the shell coarser
    return mesh_labels(three_labels(), kRegions, s);
  }();
  return mesh;
}

const VolumeMesh::SurfaceReport& surface(const VolumeMesh& mesh, const std::string& name) {
  for (const auto& s : mesh.surfaces)
    if (s.name == name) return s;
  throw std::runtime_error("no surface " + name);
}

TEST(SurfaceSmoothness, AnIcosahedronsNeighboursMeetAtItsDihedralAngle) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  const std::vector<Point3> p = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  const std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const std::vector<double> angles = neighbour_normal_angles_deg(p, faces);
  ASSERT_EQ(angles.size(), 30u);  // every edge once
  // Between the normals: 180 degrees less the dihedral angle arccos(-sqrt(5)/3).
  const double expected = 180 - std::acos(-std::sqrt(5.0) / 3) * 180 / M_PI;
  for (double a : angles) EXPECT_NEAR(a, expected, 1e-9);
}

TEST(ConformingMesh, EveryRegionAndInterfaceIsASmoothSurfaceThatFollowsItsLabels) {
  const VolumeMesh& mesh = conforming();
  EXPECT_TRUE(mesh.closed_manifold);
  EXPECT_EQ(mesh.quality.inverted + mesh.quality.degenerate, 0);
  // The three interfaces and the shell's outside, each smooth (the voted path: 58 and 89 degrees).
  for (const char* name : {"shell_outside", "shell_liquid", "shell_core", "liquid_core"}) {
    const auto& s = surface(mesh, name);
    SCOPED_TRACE(name);
    EXPECT_GT(s.triangles, 20);
    EXPECT_LE(s.median_angle_deg, 10);
    EXPECT_LE(s.p99_angle_deg, 35);
    EXPECT_LE(s.max_distance_mm, std::sqrt(3.0));  // a voxel's diagonal
  }
  // Each region's volume: within 1 % of its voxels', counted here.
  const MaskVolume labels = three_labels();
  std::array<double, 4> voxels{};
  for (std::uint8_t l : labels.data) voxels[l] += 1e-9;
  ASSERT_EQ(mesh.regions.size(), 3u);
  for (int r = 0; r < 3; ++r) EXPECT_NEAR(mesh.regions[std::size_t(r)].volume_m3 / voxels[std::size_t(r + 1)], 1, 0.01) << kRegions[std::size_t(r)].name;
  // The nodes of the shell's outside lie on the sphere of radius 30 mm (within a voxel).
  std::set<int> outer;
  for (const auto& t : mesh.boundary) outer.insert(t.begin(), t.end());
  for (int v : outer) {
    const auto& x = mesh.nodes_m[std::size_t(v)];
    const double r = std::sqrt(std::pow(x[0] * 1e3 - kCentre, 2) + std::pow(x[1] * 1e3 - kCentre, 2) + std::pow(x[2] * 1e3 - kCentre, 2));
    EXPECT_NEAR(r, kShellOuter - 0.5, 1.0);  // the voxels' boundary lies half a voxel inside the radius
  }
}

TEST(ConformingMesh, TheInterfacesAreSharedFaceForFaceAndTheCurveOfThreeRegionsIsKept) {
  const VolumeMesh& mesh = conforming();
  // Every face is in one element (the boundary) or two; a face in two elements of different regions
  // is an interface face, and the report lists exactly those.
  std::map<std::array<int, 3>, std::vector<int>> faces;
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> k{mesh.tetrahedra[t][kTetFace[f][0]], mesh.tetrahedra[t][kTetFace[f][1]], mesh.tetrahedra[t][kTetFace[f][2]]};
      std::sort(k.begin(), k.end());
      faces[k].push_back(int(t));
    }
  long between = 0;
  for (const auto& [k, elements] : faces) {
    ASSERT_LE(elements.size(), 2u);
    if (elements.size() == 2 && mesh.region[std::size_t(elements[0])] != mesh.region[std::size_t(elements[1])]) ++between;
  }
  EXPECT_EQ(between, mesh.interface_triangles);
  // The circle where shell, liquid and core meet: edges of all three interfaces. Its nodes lie where
  // the core's sphere meets the shell's inner sphere: z = (22^2 - 9^2 + 15^2) / (2 * 15) above the
  // centre, on a circle of radius sqrt(22^2 - z^2) (within a voxel and a half; the voxels' spheres
  // are half a voxel smaller).
  std::map<int, std::set<int>> surfaces_of;
  int index = 0;
  for (const auto& group : {std::array<int, 2>{0, 1}, std::array<int, 2>{0, 2}, std::array<int, 2>{1, 2}}) {
    for (std::size_t f = 0; f < mesh.interfaces.size(); ++f)
      if (mesh.interface_regions[f] == group)
        for (int v : mesh.interfaces[f]) surfaces_of[v].insert(index);
    ++index;
  }
  const double z = (kShellInner * kShellInner - kCoreRadius * kCoreRadius + kCoreHeight * kCoreHeight) / (2 * kCoreHeight);
  const double rho = std::sqrt(kShellInner * kShellInner - z * z);
  int on_curve = 0;
  for (const auto& [v, in] : surfaces_of) {
    if (in.size() < 3) continue;
    ++on_curve;
    const auto& x = mesh.nodes_m[std::size_t(v)];
    const double dx = x[0] * 1e3 - kCentre, dy = x[1] * 1e3 - kCentre, dz = x[2] * 1e3 - kCentre;
    EXPECT_NEAR(dz, z, 1.5);
    EXPECT_NEAR(std::sqrt(dx * dx + dy * dy), rho, 1.5);
  }
  EXPECT_GE(on_curve, 8);  // the circle (2 pi 6.2 mm long) is resolved by edges of about 2.5 mm
}

TEST(ConformingMesh, RegionSizesGradeTheElements) {
  const VolumeMesh& mesh = conforming();
  std::array<double, 3> edge{}, count{};
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const auto& e = mesh.tetrahedra[t];
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const auto &p = mesh.nodes_m[std::size_t(e[std::size_t(a)])], &q = mesh.nodes_m[std::size_t(e[std::size_t(b)])];
        edge[std::size_t(mesh.region[t])] += std::sqrt(std::pow(p[0] - q[0], 2) + std::pow(p[1] - q[1], 2) + std::pow(p[2] - q[2], 2));
        count[std::size_t(mesh.region[t])] += 1;
      }
  }
  const double shell = edge[0] / count[0] * 1e3, core = edge[2] / count[2] * 1e3;
  EXPECT_LT(core, 0.7 * shell) << "core " << core << " mm, shell " << shell << " mm";
  EXPECT_LT(core, 3.2);
}

TEST(ConformingMesh, TheVotedPathsInterfacesAreStaircasesByTheSameMeasure) {
  // The same labels meshed as one union and the regions voted onto its elements: the interfaces follow
  // element faces, and the report says so (the reason for the conforming mesher).
  MeshingSettings s;
  s.element_size_mm = 4;
  MaskVolume labels = three_labels(), mask = labels;
  for (auto& v : mask.data) v = v != 0;
  VolumeMesh voted = mesh_mask(mask, s);
  assign_regions(voted, labels, kRegions);
  voted.surfaces = surface_smoothness(voted, labels, kRegions);
  EXPECT_GT(surface(voted, "shell_liquid").median_angle_deg, 30);
  EXPECT_LT(surface(voted, "shell_outside").median_angle_deg, 10);  // the union's own surface is smooth
}

TEST(ConformingMesh, AMeshShortOfTheAngleIsMadeAgainFromOtherSeedsAndTheBestKept) {
  // The first mesh's smallest angle, then the same asked a hair above it: the first seed falls
  // short, so the mesher must try others, keep one no worse than the first, and say whether it met
  // the angle by the angle it has.
  MeshingSettings s;
  s.element_size_mm = 6;
  const MaskVolume labels = three_labels();
  const VolumeMesh first = mesh_labels(labels, kRegions, s);
  ASSERT_EQ(first.attempts.size(), 1u) << "the first seed already fell short of " << s.min_dihedral_deg;
  s.min_dihedral_deg = first.quality.min_dihedral_deg + 1e-3;
  const VolumeMesh again = mesh_labels(labels, kRegions, s);
  ASSERT_GE(again.attempts.size(), 2u);
  EXPECT_LE(again.attempts.size(), 4u);  // the mesher's four seeds
  EXPECT_EQ(std::set<std::string>(again.attempts.begin(), again.attempts.end()).size(), again.attempts.size());
  EXPECT_EQ(again.attempts.front(), first.path);
  EXPECT_GE(again.quality.min_dihedral_deg, first.quality.min_dihedral_deg);
  EXPECT_EQ(again.quality_met, again.quality.min_dihedral_deg >= s.min_dihedral_deg);
  if (!again.quality_met) EXPECT_EQ(again.attempts.size(), 4u);  // all tried before giving up
  else EXPECT_EQ(again.path, again.attempts.back());              // the one that met it, the last tried
}

TEST(ConformingMesh, BadRequestsAreRefusedWithTheirReason) {
  MeshingSettings s;
  const MaskVolume labels = three_labels();
  EXPECT_THROW(mesh_labels(labels, {}, s), std::invalid_argument);
  EXPECT_THROW(mesh_labels(labels, {{"a", {1}}, {"b", {1, 2}}}, s), std::invalid_argument);
  EXPECT_THROW(mesh_labels(labels, {{"nothing", {9}}}, s), std::runtime_error);
  s.region_size_mm = {-1};
  EXPECT_THROW(mesh_labels(labels, {{"shell", {1}}}, s), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::meshes
