// The smooth surfaces the trainer draws over a mesh with voted regions (app/trainer/label_surfaces.h),
// against closed forms: a P1 embedding carries an affine displacement exactly, and the surfaces of
// nested balls lie on the balls, face out of their region, name the region across and are smooth.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "app/trainer/label_surfaces.h"
#include "config/scene_loader.h"
#include "imaging/volume_io.h"
#include "meshes/interface_quality.h"

namespace fetouch::app::trainer {
namespace {

using Point = std::array<double, 3>;

// A cube of side `size` (m) centred on the origin, n^3 cubes each cut into six tetrahedra (Kuhn),
// every tetrahedron of material `material(centroid)`.
template <class Material>
MeshView block(int n, double size, Material material) {
  MeshView m;
  const double h = size / n;
  const auto node = [n](int i, int j, int k) { return static_cast<unsigned int>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.points.push_back({i * h - size / 2, j * h - size / 2, k * h - size / 2});
  static constexpr int kPaths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& path : kPaths) {
          int at[3] = {i, j, k};
          std::array<unsigned int, 4> t{};
          t[0] = node(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[path[s]];
            t[std::size_t(s) + 1] = node(at[0], at[1], at[2]);
          }
          Point c{0, 0, 0};
          for (unsigned int v : t)
            for (int d = 0; d < 3; ++d) c[d] += m.points[v][d] / 4;
          m.tetrahedron_cell.push_back(static_cast<unsigned int>(m.tetrahedra.size()));
          m.tetrahedra.push_back(t);
          m.material.push_back(material(c));
        }
  m.cells = static_cast<unsigned int>(m.tetrahedra.size());
  return m;
}

TEST(LabelSurfaces, EmbeddedPointsCarryAnAffineDisplacementExactlyInsideAndOutTheMesh) {
  const MeshView mesh = block(4, 0.04, [](const Point&) { return 1u; });
  std::mt19937 random(7);
  std::uniform_real_distribution<double> inside(-0.0199, 0.0199), around(-0.024, 0.024);
  std::vector<Point> points;
  for (int i = 0; i < 200; ++i) points.push_back({inside(random), inside(random), inside(random)});
  for (int i = 0; i < 50; ++i) points.push_back({around(random), around(random), 0.0215});  // up to 4 mm outside
  std::vector<unsigned int> tetrahedron;
  std::vector<std::array<float, 4>> weights;
  embed_points(mesh, points, tetrahedron, weights);
  ASSERT_EQ(tetrahedron.size(), points.size());
  // u = A x + b at the nodes; P1 reproduces it everywhere, and its affine map beyond the elements.
  const double A[3][3] = {{0.10, -0.20, 0.05}, {0.03, 0.15, -0.12}, {-0.07, 0.02, 0.30}}, b[3] = {1e-3, -2e-3, 5e-4};
  const auto u = [&](const Point& x, int d) { return A[d][0] * x[0] + A[d][1] * x[1] + A[d][2] * x[2] + b[d]; };
  double worst = 0;
  for (std::size_t p = 0; p < points.size(); ++p) {
    const auto& t = mesh.tetrahedra[tetrahedron[p]];
    float least = 1;
    for (int d = 0; d < 3; ++d) {
      double carried = 0;
      for (int c = 0; c < 4; ++c) carried += weights[p][std::size_t(c)] * u(mesh.points[t[std::size_t(c)]], d);
      worst = std::max(worst, std::abs(carried - u(points[p], d)));
    }
    for (float w : weights[p]) least = std::min(least, w);
    if (p < 200) {
      EXPECT_GE(least, -1e-5f) << "a point inside the mesh is inside the element that carries it";
    }
  }
  EXPECT_LT(worst, 1e-8) << "m; the displacement is up to about 1e-2 m";
}

TEST(LabelSurfaces, NestedBallsDrawSmoothSurfacesOnTheBallsFacingOutOfTheirRegion) {
  // Labels on a 1 mm grid: 1 a ball of radius 28 mm, 2 a ball of 18 mm inside it, 3 a ball of 7 mm
  // off its centre. Regions a = {1}, b = {2}, c = {3}; the mesh, 6 mm elements, votes them by centroid.
  struct Ball {
    Point centre;
    double radius;
  };
  const Ball outer{{0, 0, 0}, 28}, middle{{0, 0, 0}, 18}, inner{{6, -3, 2}, 7};
  const auto inside = [](const Ball& s, const Point& x) {
    return std::hypot(x[0] - s.centre[0], x[1] - s.centre[1], x[2] - s.centre[2]) <= s.radius;
  };
  const auto label_at = [&](const Point& x_mm) -> std::uint8_t {
    return inside(inner, x_mm) ? 3 : inside(middle, x_mm) ? 2 : inside(outer, x_mm) ? 1 : 0;
  };
  imaging::Volume<std::uint8_t> labels;
  labels.dimensions = {71, 71, 71};
  labels.origin_mm = {-35, -35, -35};
  labels.data.resize(71 * 71 * 71);
  for (int k = 0; k < 71; ++k)
    for (int j = 0; j < 71; ++j)
      for (int i = 0; i < 71; ++i) labels.data[labels.index(i, j, k)] = label_at(labels.position_mm(i, j, k));
  MeshView mesh = block(10, 0.06, [&](const Point& c) { return static_cast<unsigned int>(label_at({1e3 * c[0], 1e3 * c[1], 1e3 * c[2]})); });
  mesh.region_name = {{1, "a"}, {2, "b"}, {3, "c"}};
  const std::vector<LabelSurface> drawn = label_surfaces(labels, {{"a", {1}}, {"b", {2}}, {"c", {3}}}, mesh);

  // b draws what it shares with a (b is the smaller), c what it shares with b; a's only other
  // side is the outside, which the mesh's boundary draws.
  ASSERT_EQ(drawn.size(), 2u);
  const Ball* shapes[] = {&middle, &inner};
  const unsigned int across[] = {1, 2};
  for (std::size_t s = 0; s < 2; ++s) {
    const LabelSurface& surface = drawn[s];
    SCOPED_TRACE("region " + std::to_string(surface.material));
    EXPECT_EQ(surface.material, s + 2);
    ASSERT_GT(surface.triangles.size(), 100u);
    ASSERT_EQ(surface.across.size(), surface.triangles.size());
    ASSERT_EQ(surface.tetrahedron.size(), surface.points.size());
    const Ball& ball = *shapes[s];
    double farthest = 0;
    for (const Point& x : surface.points)
      farthest = std::max(farthest, std::abs(std::hypot(1e3 * x[0] - ball.centre[0], 1e3 * x[1] - ball.centre[1],
                                                        1e3 * x[2] - ball.centre[2]) - ball.radius));
    EXPECT_LT(farthest, 0.87) << "mm from the ball (half a voxel's diagonal)";
    long outward = 0;
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      EXPECT_EQ(surface.across[t], across[s]);
      const auto& tri = surface.triangles[t];
      const Point &p = surface.points[tri[0]], &q = surface.points[tri[1]], &r = surface.points[tri[2]];
      const Point e{q[0] - p[0], q[1] - p[1], q[2] - p[2]}, f{r[0] - p[0], r[1] - p[1], r[2] - p[2]};
      const Point n{e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
      double radial = 0;
      for (int d = 0; d < 3; ++d) radial += n[d] * ((p[d] + q[d] + r[d]) / 3 - 1e-3 * ball.centre[d]);
      outward += radial > 0;
    }
    EXPECT_EQ(outward, static_cast<long>(surface.triangles.size())) << "every triangle faces out of its region";
    // Against the mesh's own interface, a staircase of element faces: the drawn surface is smooth.
    std::vector<std::array<int, 3>> triangles;
    for (const auto& t : surface.triangles) triangles.push_back({int(t[0]), int(t[1]), int(t[2])});
    std::vector<double> angles = meshes::neighbour_normal_angles_deg(surface.points, triangles);
    ASSERT_FALSE(angles.empty());
    std::sort(angles.begin(), angles.end());
    EXPECT_LE(angles[angles.size() / 2], 10);
    EXPECT_LE(angles[std::size_t(0.99 * double(angles.size() - 1))], 35);
  }
}

TEST(LabelSurfaces, TheLabelMapOfAVolumeSceneIsTheOneItsFileHolds) {
  // A scene whose voted regions come from a label-map file reads that file's labels for its
  // surfaces; one with `surface: conforming` (its interfaces are surfaces already) reads none.
  imaging::Volume<std::uint8_t> written;
  written.dimensions = {12, 10, 8};
  written.spacing_mm = {1.0, 1.5, 2.0};
  written.origin_mm = {-5, 3, 7};
  written.data.resize(12 * 10 * 8);
  for (std::size_t i = 0; i < written.data.size(); ++i) written.data[i] = static_cast<std::uint8_t>(i % 3);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("fetouch_label_surfaces_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  imaging::write_volume(written, dir / "labels.mha");
  const auto scene = [&](const std::string& surface) {
    return config::parse_scene("name: labels\nmesh:\n  volume: labels.mha\n  meshing:\n    regions: {a: [1], b: [2]}\n"
                               "    target_size_m: 0.004\n    surface: " + surface + "\n"
                               "materials:\n  a: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.45}\n"
                               "  b: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.45}\n",
                               "labels.yaml", dir)
        .scene;
  };
  const auto read = scene_label_map(scene("contoured"));
  ASSERT_TRUE(read);
  EXPECT_EQ(read->dimensions, written.dimensions);
  EXPECT_EQ(read->spacing_mm, written.spacing_mm);
  EXPECT_EQ(read->origin_mm, written.origin_mm);
  EXPECT_EQ(read->data, written.data);
  EXPECT_FALSE(scene_label_map(scene("conforming")));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::app::trainer
