// Tetrahedral geometry and sliver repair against closed forms: a regular and a corner
// tetrahedron's dihedral angles, a unit cube's boundary (divergence theorem), pinched meshes, and
// each repair operation on a configuration whose answer is known, and the boundary moved out to a
// volume on an icosahedron (whose vertex normals are radial by symmetry, so the offset is known).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "meshes/tet_repair.h"

namespace fetouch::meshes {
namespace {

double total_volume(const std::vector<Point3>& nodes, const std::vector<Tet>& tets) {
  double v = 0;
  for (const Tet& t : tets) v += tet_signed_volume(nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]);
  return v;
}

double worst(const std::vector<Point3>& nodes, const std::vector<Tet>& tets) {
  double q = 180;
  for (const Tet& t : tets) q = std::min(q, min_dihedral_deg(nodes, t));
  return q;
}

// A row of `cubes` unit cubes along x, each as six tetrahedra around its diagonal (Kuhn's split);
// node (i, j, k) is i + (cubes + 1) (j + 2 k).
void cube_row(int cubes, std::vector<Point3>& nodes, std::vector<Tet>& tets) {
  nodes.clear(), tets.clear();
  const auto id = [cubes](int i, int j, int k) { return i + (cubes + 1) * (j + 2 * k); };
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i <= cubes; ++i) nodes.push_back({double(i), double(j), double(k)});
  const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int c = 0; c < cubes; ++c)
    for (const auto& path : paths) {
      int x[3] = {c, 0, 0};
      Tet t;
      t[0] = id(c, 0, 0);
      for (int s = 0; s < 3; ++s) {
        ++x[path[s]];
        t[s + 1] = id(x[0], x[1], x[2]);
      }
      if (tet_signed_volume(nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]) < 0) std::swap(t[2], t[3]);
      tets.push_back(t);
    }
}

void unit_cube(std::vector<Point3>& nodes, std::vector<Tet>& tets) { cube_row(1, nodes, tets); }

void orient(const std::vector<Point3>& nodes, std::vector<Tet>& tets) {
  for (Tet& t : tets)
    if (tet_signed_volume(nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]) < 0) std::swap(t[2], t[3]);
}

TEST(TetGeometry, DihedralAnglesOfKnownTetrahedra) {
  const double regular = std::acos(1.0 / 3) * 180 / M_PI;  // 70.53 degrees
  const auto a = dihedral_angles_deg({1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1});
  for (double angle : a) EXPECT_NEAR(angle, regular, 1e-9);
  // The corner of a cube: right angles at the three edges from the corner, acos(1/sqrt 3) at the
  // edges of the far face.
  auto c = dihedral_angles_deg({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  std::sort(c.begin(), c.end());
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(c[k], std::acos(1 / std::sqrt(3.0)) * 180 / M_PI, 1e-9);
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(c[k], 90, 1e-9);
  // An inverted element has no quality.
  EXPECT_EQ(min_dihedral_deg({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 2, 1, 3}), 0);
}

TEST(TetGeometry, CubeBoundaryIsClosedOutwardAndEnclosesItsVolume) {
  std::vector<Point3> nodes;
  std::vector<Tet> tets;
  unit_cube(nodes, tets);
  EXPECT_NEAR(total_volume(nodes, tets), 1, 1e-14);
  const auto faces = boundary_faces(tets);
  ASSERT_EQ(faces.size(), 12u);
  // Divergence theorem with F = x / 3: the volume is the sum over faces of (centroid . n) area / 3,
  // positive only if every face points out.
  double flux = 0;
  for (const Triangle& f : faces) {
    const Point3 &p = nodes[f[0]], &q = nodes[f[1]], &r = nodes[f[2]];
    const Point3 u{q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v{r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    const Point3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};  // 2 area n
    for (int k = 0; k < 3; ++k) flux += (p[k] + q[k] + r[k]) / 3 * n[k] / 2 / 3;
  }
  EXPECT_NEAR(flux, 1, 1e-14);
  EXPECT_TRUE(boundary_is_closed_manifold(tets));
}

TEST(TetGeometry, PinchedMeshesAreNotManifold) {
  // Two tetrahedra touching at one node: each boundary edge has two faces, but the node's faces
  // make two fans.
  const std::vector<Tet> at_a_node{{0, 1, 2, 3}, {0, 4, 5, 6}};
  EXPECT_FALSE(boundary_is_closed_manifold(at_a_node));
  // Touching along an edge: four boundary faces on that edge.
  const std::vector<Tet> at_an_edge{{0, 1, 2, 3}, {0, 1, 4, 5}};
  EXPECT_FALSE(boundary_is_closed_manifold(at_an_edge));
  // A face held by three elements.
  const std::vector<Tet> three_on_a_face{{0, 1, 2, 3}, {0, 2, 1, 4}, {0, 1, 2, 5}};
  EXPECT_FALSE(boundary_is_closed_manifold(three_on_a_face));
  EXPECT_TRUE(boundary_is_closed_manifold({{0, 1, 2, 3}}));
}

TEST(SliverRepair, FlipsAwayASliverOnTheSurface) {
  // The cube's top corners (1,0,1) and (0,1,1) raised by eps, and a sliver filling the fold
  // between the top's two diagonals: with the two elements under it, three around the top
  // diagonal, which a 3-2 flip makes two, keeping the boundary and the volume.
  std::vector<Point3> nodes;
  std::vector<Tet> tets;
  unit_cube(nodes, tets);
  const double eps = 0.02;
  nodes[5][2] += eps, nodes[6][2] += eps;  // (1,0,1), (0,1,1)
  tets.push_back({4, 5, 7, 6});
  orient(nodes, tets);
  ASSERT_TRUE(boundary_is_closed_manifold(tets));
  const double volume = total_volume(nodes, tets);
  ASSERT_LT(worst(nodes, tets), 5);

  const SliverRepair r = repair_slivers(nodes, tets, 10);
  EXPECT_EQ(r.flips32, 1);
  EXPECT_EQ(r.peeled, 0);
  EXPECT_EQ(tets.size(), 6u);
  EXPECT_TRUE(boundary_is_closed_manifold(tets));
  EXPECT_NEAR(total_volume(nodes, tets), volume, 1e-14);
  EXPECT_GT(r.min_dihedral_after_deg, 10);
  EXPECT_DOUBLE_EQ(r.min_dihedral_after_deg, worst(nodes, tets));
}

TEST(SliverRepair, PeelsASliverThatNoFlipRemoves) {
  // Two cubes side by side, the edge their tops share lowered by eps into a valley, and a sliver
  // filling the valley from corner (0,0,1) to corner (2,1,1). Five elements around the valley's
  // edge (no 3-2 flip), no 2-3 flip valid, every node on a corner or an edge of the box (none
  // moves): it is peeled, its volume eps / 3 with it.
  std::vector<Point3> nodes;
  std::vector<Tet> tets;
  cube_row(2, nodes, tets);
  const auto id = [](int i, int j, int k) { return i + 3 * (j + 2 * k); };
  const double eps = 0.02;
  nodes[id(1, 0, 1)][2] -= eps, nodes[id(1, 1, 1)][2] -= eps;
  tets.push_back({id(0, 0, 1), id(1, 0, 1), id(1, 1, 1), id(2, 1, 1)});
  orient(nodes, tets);
  ASSERT_TRUE(boundary_is_closed_manifold(tets));
  const double volume = total_volume(nodes, tets);
  ASSERT_LT(worst(nodes, tets), 5);

  const SliverRepair r = repair_slivers(nodes, tets, 10);
  EXPECT_EQ(r.peeled, 1);
  EXPECT_EQ(r.flips23 + r.flips32 + r.relocated, 0);
  EXPECT_NEAR(r.peeled_volume, eps / 3, 1e-14);
  EXPECT_EQ(tets.size(), 12u);
  EXPECT_TRUE(boundary_is_closed_manifold(tets));
  EXPECT_NEAR(total_volume(nodes, tets), volume - eps / 3, 1e-14);
  EXPECT_GT(r.min_dihedral_after_deg, 10);
}

// A bipyramid: the triangle (c, d, e) on the unit circle in z = 0 and apexes a, b at z = +-h.
std::vector<Point3> bipyramid(double h) {
  std::vector<Point3> nodes{{0, 0, h}, {0, 0, -h}};
  for (int k = 0; k < 3; ++k) nodes.push_back({std::cos(2 * M_PI * k / 3), std::sin(2 * M_PI * k / 3), 0});
  return nodes;
}

std::set<Triangle> sorted_faces(const std::vector<Tet>& tets) {
  std::set<Triangle> out;
  for (Triangle f : boundary_faces(tets)) {
    std::sort(f.begin(), f.end());
    out.insert(f);
  }
  return out;
}

TEST(SliverRepair, FlatPairBecomesThreeAroundTheAxis) {
  // Low and wide (h = 0.15): two flat elements on the triangle; three around the axis a-b are
  // better. The bipyramid's volume is 2/3 h times the triangle's area 3 sqrt(3) / 4.
  std::vector<Point3> nodes = bipyramid(0.15);
  std::vector<Tet> tets{{2, 3, 4, 0}, {2, 3, 4, 1}};
  orient(nodes, tets);
  const auto faces = sorted_faces(tets);
  const double before = worst(nodes, tets);
  const SliverRepair r = repair_slivers(nodes, tets, before + 1);
  EXPECT_EQ(r.flips23, 1);
  ASSERT_EQ(tets.size(), 3u);
  for (const Tet& t : tets) EXPECT_TRUE(std::count(t.begin(), t.end(), 0) && std::count(t.begin(), t.end(), 1));
  EXPECT_NEAR(total_volume(nodes, tets), 2.0 / 3 * 0.15 * 3 * std::sqrt(3.0) / 4, 1e-14);
  EXPECT_EQ(sorted_faces(tets), faces);  // the boundary is unchanged
  EXPECT_GT(worst(nodes, tets), before);
}

TEST(SliverRepair, NeedlesAroundALongAxisBecomeTwo) {
  // Tall (h = 2): three needles around the axis; two elements on the triangle are better.
  std::vector<Point3> nodes = bipyramid(2);
  std::vector<Tet> tets{{0, 1, 2, 3}, {0, 1, 3, 4}, {0, 1, 4, 2}};
  orient(nodes, tets);
  const auto faces = sorted_faces(tets);
  const double before = worst(nodes, tets);
  const SliverRepair r = repair_slivers(nodes, tets, before + 1);
  EXPECT_EQ(r.flips32, 1);
  ASSERT_EQ(tets.size(), 2u);
  EXPECT_NEAR(total_volume(nodes, tets), 2.0 / 3 * 2 * 3 * std::sqrt(3.0) / 4, 1e-13);
  EXPECT_EQ(sorted_faces(tets), faces);
  EXPECT_GT(worst(nodes, tets), before);
}

TEST(SliverRepair, MovesAnInteriorNodeBackTowardsTheCentre) {
  // The octahedron |x| + |y| + |z| <= 1 as eight corner elements around its centre; the centre
  // pushed next to a face makes slivers there. At the centre every element is a cube corner
  // (smallest angle acos(1/sqrt 3) = 54.7 degrees).
  std::vector<Point3> nodes{{0.3, 0.3, 0.35}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<Tet> tets;
  for (int x : {1, 2})
    for (int y : {3, 4})
      for (int z : {5, 6}) tets.push_back({0, x, y, z});
  orient(nodes, tets);
  ASSERT_LT(worst(nodes, tets), 10);
  const SliverRepair r = repair_slivers(nodes, tets, 50);
  EXPECT_GT(r.relocated, 0);
  EXPECT_EQ(tets.size(), 8u);
  EXPECT_NEAR(total_volume(nodes, tets), 4.0 / 3, 1e-14);
  EXPECT_GT(worst(nodes, tets), 45);
  for (int k = 1; k < 7; ++k) EXPECT_EQ(std::abs(nodes[k][0]) + std::abs(nodes[k][1]) + std::abs(nodes[k][2]), 1);
}

// A regular icosahedron of circumradius 1 as 20 tetrahedra about its centre: its 12 boundary nodes'
// normals are radial by symmetry, so moving them by d scales it by 1 + d and the offset that gives a
// volume V is (V / V0)^(1/3) - 1, with V0 = 5/12 (3 + sqrt 5) a^3 and a = 1 / sin(2 pi / 5).
TEST(RestoreVolume, AnIcosahedronGrowsToTheSpheresVolume) {
  const double phi = (1 + std::sqrt(5.0)) / 2, scale = 1 / std::sqrt(1 + phi * phi);
  std::vector<Point3> nodes{{0, 0, 0}};
  for (const double s1 : {-1.0, 1.0})
    for (const double s2 : {-1.0, 1.0}) {
      nodes.push_back({0, s1 * scale, s2 * phi * scale});
      nodes.push_back({s1 * scale, s2 * phi * scale, 0});
      nodes.push_back({s2 * phi * scale, 0, s1 * scale});
    }
  // The faces: the triples of vertices at the edge length from one another.
  const double edge = 2 * scale;
  const auto dist = [&](int a, int b) {
    return std::sqrt(std::pow(nodes[a][0] - nodes[b][0], 2) + std::pow(nodes[a][1] - nodes[b][1], 2) +
                     std::pow(nodes[a][2] - nodes[b][2], 2));
  };
  std::vector<Tet> tets;
  for (int a = 1; a <= 12; ++a)
    for (int b = a + 1; b <= 12; ++b)
      for (int c = b + 1; c <= 12; ++c)
        if (std::abs(dist(a, b) - edge) < 1e-9 && std::abs(dist(b, c) - edge) < 1e-9 && std::abs(dist(a, c) - edge) < 1e-9) {
          Tet t{0, a, b, c};
          if (tet_signed_volume(nodes[0], nodes[a], nodes[b], nodes[c]) < 0) std::swap(t[2], t[3]);
          tets.push_back(t);
        }
  ASSERT_EQ(tets.size(), 20u);
  const double a = 1 / std::sin(2 * M_PI / 5);
  const double v0 = 5.0 / 12 * (3 + std::sqrt(5.0)) * a * a * a;
  ASSERT_NEAR(total_volume(nodes, tets), v0, 1e-12);

  const double sphere = 4 * M_PI / 3;
  std::vector<Point3> grown = nodes;
  const double offset = restore_volume(grown, tets, sphere, 0.5, 10);
  EXPECT_NEAR(offset, std::cbrt(sphere / v0) - 1, 1e-9);
  EXPECT_NEAR(total_volume(grown, tets), sphere, 1e-9);
  EXPECT_EQ(grown[0], nodes[0]);  // the centre is no boundary node
  for (int v = 1; v <= 12; ++v) EXPECT_NEAR(std::sqrt(grown[v][0] * grown[v][0] + grown[v][1] * grown[v][1] + grown[v][2] * grown[v][2]), 1 + offset, 1e-12);

  // Held at the bound: a tenth of the offset needed.
  const double bound = 0.1 * offset;
  std::vector<Point3> held = nodes;
  EXPECT_DOUBLE_EQ(restore_volume(held, tets, sphere, bound, 10), bound);
  EXPECT_NEAR(total_volume(held, tets), v0 * std::pow(1 + bound, 3), 1e-12);
  // With the inner node 90 % of the way to a face's centre, shrinking to half the volume moves that
  // face past it and turns its element over: nothing moves.
  std::vector<Point3> kept = nodes;
  for (int k = 0; k < 3; ++k) kept[0][k] = 0.9 / 3 * (nodes[tets[0][1]][k] + nodes[tets[0][2]][k] + nodes[tets[0][3]][k]);
  const std::vector<Point3> off_centre = kept;
  EXPECT_EQ(restore_volume(kept, tets, 0.5 * v0, 0.5, 0), 0);
  EXPECT_EQ(kept, off_centre);
  // A smaller shrink leaves the face outside the node: it is made.
  EXPECT_LT(restore_volume(kept, tets, 0.9 * v0, 0.5, 0), 0);
  EXPECT_NEAR(total_volume(kept, tets), 0.9 * v0, 1e-9);
}

// An n-gonal bipyramid: the regular n-gon on the unit circle in z = 0 (nodes 2..n+1), its first
// node pulled to radius r, and apexes 0 and 1 at z = +-1; n elements around the axis 0-1, the two
// beside the pulled node flat (a sliver each).
void pulled_ring(int n, double r, std::vector<Point3>& nodes, std::vector<Tet>& tets) {
  nodes = {{0, 0, 1}, {0, 0, -1}};
  tets.clear();
  for (int k = 0; k < n; ++k) nodes.push_back({std::cos(2 * M_PI * k / n), std::sin(2 * M_PI * k / n), 0});
  nodes[2] = {r, 0, 0};
  for (int k = 0; k < n; ++k) tets.push_back({0, 1, 2 + k, 2 + (k + 1) % n});
  orient(nodes, tets);
}

TEST(SliverRepair, RingsOfFourToSevenAroundAnEdgeLoseIt) {
  // Without the axis, 2 (n - 2) elements over a triangulation of the ring (a 4-4 flip for n = 4,
  // an edge removal above). Region-aware repair only (the other paths' meshes are kept as they
  // were). The volume is 2/3 times the ring polygon's area (the shoelace formula).
  for (int n = 4; n <= 7; ++n) {
    SCOPED_TRACE(n);
    std::vector<Point3> nodes;
    std::vector<Tet> tets;
    pulled_ring(n, 0.1, nodes, tets);
    double area = 0;
    for (int k = 0; k < n; ++k) {
      const Point3 &p = nodes[std::size_t(2 + k)], &q = nodes[std::size_t(2 + (k + 1) % n)];
      area += 0.5 * (p[0] * q[1] - q[0] * p[1]);
    }
    std::vector<int> region(tets.size(), 0);
    const auto faces = sorted_faces(tets);
    ASSERT_LT(worst(nodes, tets), 10);
    const SliverRepair r = repair_slivers(nodes, tets, 10, &region);
    EXPECT_EQ(n == 4 ? r.flips44 : r.edge_removals, 1);
    EXPECT_EQ(r.peeled, 0);
    ASSERT_EQ(tets.size(), std::size_t(2 * (n - 2)));
    ASSERT_EQ(region.size(), tets.size());
    for (const Tet& t : tets) EXPECT_FALSE(std::count(t.begin(), t.end(), 0) && std::count(t.begin(), t.end(), 1));
    EXPECT_NEAR(total_volume(nodes, tets), 2.0 / 3 * area, 1e-12);
    EXPECT_EQ(sorted_faces(tets), faces);
    EXPECT_GT(worst(nodes, tets), 10);

    // Without regions no 4-4 flip or edge removal (the restricted and contoured paths' repair is
    // unchanged).
    pulled_ring(n, 0.1, nodes, tets);
    const SliverRepair plain = repair_slivers(nodes, tets, 10);
    EXPECT_EQ(plain.flips44 + plain.edge_removals, 0);
  }
}

TEST(SliverRepair, AFlatCapOnAnInterfaceChangesSidesAndIsFlippedAway) {
  // The unit square at z = 0 with corners 1 and 3 raised by eps. Below, region 1 (two elements to
  // S) meets region 0 along the valley 0-2; a flat cap (0, 1, 2, 3) in region 0 fills the fold up
  // to the ridge 1-3, under a fan of seven region-0 elements around the ridge (eight around it with
  // the cap: no flip in region 0 removes the cap). The cap moves to region 1, whose 3-2 flip around
  // the valley removes it: the interface becomes the ridge's two triangles.
  const double eps = 0.02;
  std::vector<Point3> nodes{{0, 0, 0}, {1, 0, eps}, {1, 1, 0}, {0, 1, eps}, {0.5, 0.5, -1}};
  const int S = 4;
  std::vector<Tet> tets{{0, 1, 2, 3}, {0, 1, 2, S}, {0, 2, 3, S}};
  std::vector<int> region{0, 1, 1};
  std::vector<int> arc{0};  // around the ridge from node 0 over the top to node 2
  const double R = std::sqrt(0.5);
  for (int i = 1; i < 7; ++i) {
    const double th = M_PI * i / 7;
    nodes.push_back({0.5 - R * std::cos(th) / std::sqrt(2.0), 0.5 - R * std::cos(th) / std::sqrt(2.0), eps + R * std::sin(th)});
    arc.push_back(static_cast<int>(nodes.size()) - 1);
  }
  arc.push_back(2);
  for (std::size_t i = 0; i + 1 < arc.size(); ++i) tets.push_back({1, 3, arc[i], arc[i + 1]}), region.push_back(0);
  orient(nodes, tets);
  ASSERT_TRUE(boundary_is_closed_manifold(tets));
  for (std::size_t t = 1; t < tets.size(); ++t) ASSERT_GT(min_dihedral_deg(nodes, tets[t]), 10);
  ASSERT_LT(min_dihedral_deg(nodes, tets[0]), 5);
  const double volume = total_volume(nodes, tets);
  const auto faces = sorted_faces(tets);
  double over = 0;  // region 0 without the cap
  for (std::size_t t = 3; t < tets.size(); ++t) over += tet_signed_volume(nodes[tets[t][0]], nodes[tets[t][1]], nodes[tets[t][2]], nodes[tets[t][3]]);

  const SliverRepair r = repair_slivers(nodes, tets, 10, &region);
  EXPECT_EQ(r.caps_moved, 1);
  EXPECT_EQ(r.flips32, 1);
  EXPECT_EQ(r.peeled, 0);
  ASSERT_EQ(tets.size(), 9u);
  EXPECT_EQ(sorted_faces(tets), faces);
  EXPECT_NEAR(total_volume(nodes, tets), volume, 1e-14);
  EXPECT_GT(worst(nodes, tets), 10);
  // Region 1 is what lies under the ridge: the pyramid from S over the raised square, as the two
  // halves of the square along the ridge.
  const double under_ridge = std::abs(tet_signed_volume(nodes[0], nodes[1], nodes[3], nodes[S])) +
                             std::abs(tet_signed_volume(nodes[1], nodes[2], nodes[3], nodes[S]));
  double in[2] = {0, 0};
  for (std::size_t t = 0; t < tets.size(); ++t)
    in[region[t]] += tet_signed_volume(nodes[tets[t][0]], nodes[tets[t][1]], nodes[tets[t][2]], nodes[tets[t][3]]);
  EXPECT_NEAR(in[1], under_ridge, 1e-14);
  EXPECT_NEAR(in[0], over, 1e-14);
  // The faces between the regions: the ridge's triangles (0, 1, 3) and (1, 2, 3).
  std::set<Triangle> interface;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (std::size_t q = t + 1; q < tets.size(); ++q) {
      if (region[t] == region[q]) continue;
      std::vector<int> common;
      for (int v : tets[t])
        if (std::count(tets[q].begin(), tets[q].end(), v)) common.push_back(v);
      if (common.size() == 3) {
        std::sort(common.begin(), common.end());
        interface.insert({common[0], common[1], common[2]});
      }
    }
  EXPECT_EQ(interface, (std::set<Triangle>{{0, 1, 3}, {1, 2, 3}}));
}

}  // namespace
}  // namespace fetouch::meshes
