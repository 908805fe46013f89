// The cavity's curved wall (quadratic elements' faces) against closed forms and finite differences:
// - The unit cube's boundary carried by the quadratic map F(X) = (X + a X^2, Y + b Z^2, Z + c X Y),
//   as 12 P2 triangles or 6 Q2 quadrilaterals with their nodes at F of theirs: P2 and Q2 interpolate
//   F exactly, so the curved faces are the image of the cube's and enclose the integral of det grad F
//   = (1 + 2 a X)(1 - 2 b c X Z) over the cube: 1 + a - b c / 2 - 2 a b c / 3.
// - The gradient and the Hessian (add_hessian's entries) against central differences of the volume.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "fem/cavity.h"

namespace fetouch::fem {
namespace {

using Vec = std::array<double, 3>;
constexpr double kA = 0.3, kB = -0.2, kC = 0.25;

Vec mapped(const Vec& x) { return {x[0] + kA * x[0] * x[0], x[1] + kB * x[2] * x[2], x[2] + kC * x[0] * x[1]}; }

// The cube's faces, each as its corners in turn seen from outside (counter-clockwise).
const int kFaces[6][4][3] = {
    {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}},  // z = 0
    {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},  // z = 1
    {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}},  // y = 0
    {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},  // y = 1
    {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}},  // x = 0
    {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}},  // x = 1
};

Vec mid(const Vec& a, const Vec& b) { return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2}; }

// The wall with shared nodes (one dof triple per distinct position) and u = F(X) - X at each.
struct Wall {
  CavityWall wall;
  std::vector<double> u;
};

Wall cube(bool quadrilaterals) {
  Wall w;
  std::map<Vec, unsigned int> index;
  const auto node = [&](const Vec& x, std::array<unsigned int, 3>& dofs, std::array<double, 3>& position) {
    auto [it, fresh] = index.emplace(x, static_cast<unsigned int>(index.size()));
    if (fresh) {
      const Vec y = mapped(x);
      for (int d = 0; d < 3; ++d) w.u.push_back(y[d] - x[d]);
    }
    for (unsigned int d = 0; d < 3; ++d) dofs[d] = 3 * it->second + d;
    position = x;
  };
  for (const auto& face : kFaces) {
    Vec c[4];
    for (int k = 0; k < 4; ++k) c[k] = {double(face[k][0]), double(face[k][1]), double(face[k][2])};
    if (quadrilaterals) {
      CavityWall::QuadraticFace q;
      q.nodes = 9;
      const Vec nodes[9] = {c[0], c[1], c[2], c[3], mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[3]), mid(c[3], c[0]),
                            mid(c[0], c[2])};
      for (int a = 0; a < 9; ++a) node(nodes[a], q.dofs[a], q.position[a]);
      w.wall.quadratic_faces.push_back(q);
    } else {
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        CavityWall::QuadraticFace q;
        q.nodes = 6;
        const Vec a = c[t[0]], b = c[t[1]], d = c[t[2]];
        const Vec nodes[6] = {a, b, d, mid(a, b), mid(b, d), mid(d, a)};
        for (int k = 0; k < 6; ++k) node(nodes[k], q.dofs[k], q.position[k]);
        w.wall.quadratic_faces.push_back(q);
      }
    }
  }
  return w;
}

TEST(CavityWall, CurvedFacesEncloseTheMappedCubesVolumeExactly) {
  const double exact = 1 + kA - kB * kC / 2 - 2 * kA * kB * kC / 3;
  for (const bool quads : {false, true}) {
    const Wall w = cube(quads);
    const std::vector<double> zero(w.u.size(), 0.0);
    EXPECT_NEAR(w.wall.volume(zero.data()), 1.0, 1e-14) << (quads ? "Q2" : "P2") << ": the undeformed cube";
    EXPECT_NEAR(w.wall.volume(w.u.data()), exact, 1e-13) << (quads ? "Q2" : "P2") << ": the mapped cube";
  }
  // Flat faces between the vertices would see the vertices only: the mapped corners' hexahedron.
  const Wall w = cube(false);
  CavityWall flat;
  for (const auto& q : w.wall.quadratic_faces) {
    CavityWall::Triangle t;
    for (int v = 0; v < 3; ++v) t.dofs[v] = q.dofs[v], t.position[v] = q.position[v];
    flat.triangles.push_back(t);
  }
  EXPECT_GT(std::abs(flat.volume(w.u.data()) - exact), 1e-3) << "the curvature is what the quadratic faces add";
}

TEST(CavityWall, CurvedFacesGradientAndHessianMatchFiniteDifferences) {
  for (const bool quads : {false, true}) {
    Wall w = cube(quads);
    for (std::size_t i = 0; i < w.u.size(); ++i) w.u[i] += 0.01 * std::sin(1.7 * i);  // a generic state
    const std::size_t n = w.u.size();
    std::vector<double> g(n, 0.0);
    w.wall.add_gradient(w.u.data(), 1.0, g.data());
    std::vector<double> h(n * n, 0.0);
    w.wall.add_hessian(w.u.data(), 1.0, [&](unsigned int r, unsigned int c, double v) { h[r * n + c] += v; });
    const double step = 1e-5;
    double worst_g = 0, worst_h = 0, largest_h = 0;
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<double> up = w.u, down = w.u;
      up[i] += step, down[i] -= step;
      const double fd = (w.wall.volume(up.data()) - w.wall.volume(down.data())) / (2 * step);
      worst_g = std::max(worst_g, std::abs(fd - g[i]));
      std::vector<double> gu(n, 0.0), gd(n, 0.0);
      w.wall.add_gradient(up.data(), 1.0, gu.data());
      w.wall.add_gradient(down.data(), 1.0, gd.data());
      for (std::size_t j = 0; j < n; ++j) {
        worst_h = std::max(worst_h, std::abs((gu[j] - gd[j]) / (2 * step) - h[j * n + i]));
        largest_h = std::max(largest_h, std::abs(h[j * n + i]));
      }
    }
    EXPECT_LT(worst_g, 1e-9) << (quads ? "Q2" : "P2");
    EXPECT_LT(worst_h, 1e-8) << (quads ? "Q2" : "P2");
    EXPECT_GT(largest_h, 0.01) << (quads ? "Q2" : "P2");
  }
}

}  // namespace
}  // namespace fetouch::fem
