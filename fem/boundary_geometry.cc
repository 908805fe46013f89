#include "fem/boundary_geometry.h"

#include <array>
#include <limits>
#include <vector>

namespace fetouch::fem {

using namespace dealii;

namespace {

// The point of triangle abc nearest p, as barycentric weights of a, b, c (Ericson, Real-Time
// Collision Detection, 5.1.5: by the Voronoi regions of the triangle's vertices and edges).
std::array<double, 3> nearest_on_triangle(const Point<3>& p, const Point<3>& a, const Point<3>& b, const Point<3>& c) {
  const Tensor<1, 3> ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Tensor<1, 3> bp = p - b;
  const double d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Tensor<1, 3> cp = p - c;
  const double d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denominator = 1 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return {1 - v - w, v, w};
}

}  // namespace

Point<3> boundary_point_nearest(const Discretisation& d, const Point<3>& x, const Vector<double>* u) {
  double best = std::numeric_limits<double>::infinity();
  Point<3> answer = x;
  std::array<Point<3>, 4> deformed;
  for (const Discretisation::BoundaryFace& face : d.boundary_faces()) {
    for (unsigned int k = 0; k < face.vertices; ++k) {
      deformed[k] = face.vertex[k];
      if (u)
        for (unsigned int c = 0; c < 3; ++c) deformed[k][c] += (*u)[face.vertex_dof[3 * k + c]];
    }
    // A quadrilateral's vertices are in lexicographic order (0 1 / 2 3): triangles 0 1 3, 0 3 2.
    static const std::array<std::array<int, 3>, 2> quad{{{0, 1, 3}, {0, 3, 2}}}, triangle{{{0, 1, 2}, {0, 1, 2}}};
    const auto& triangles = face.vertices == 4 ? quad : triangle;
    for (const auto& t : triangles) {
      const auto w = nearest_on_triangle(x, deformed[t[0]], deformed[t[1]], deformed[t[2]]);
      Point<3> y, X;
      for (int i = 0; i < 3; ++i) {
        y += w[i] * Tensor<1, 3>(deformed[t[i]]);
        X += w[i] * Tensor<1, 3>(face.vertex[t[i]]);
      }
      const double dist = y.distance_square(x);
      if (dist < best) best = dist, answer = X;
    }
  }
  return answer;
}

}  // namespace fetouch::fem
