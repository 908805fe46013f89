#include "fem/cavity.h"

#include <cmath>

namespace fetouch::fem {

double CavityLaw::pressure(double volume, double reference_volume) const {
  if (gas) return initial_pressure_pa * reference_volume / volume;
  return initial_pressure_pa - bulk_modulus_pa * (volume - reference_volume) / reference_volume;
}

double CavityLaw::volume(double pressure, double reference_volume) const {
  if (gas) return initial_pressure_pa * reference_volume / pressure;
  return reference_volume * (1 - (pressure - initial_pressure_pa) / bulk_modulus_pa);
}

double CavityLaw::volume_derivative(double pressure, double reference_volume) const {
  if (gas) return -initial_pressure_pa * reference_volume / (pressure * pressure);
  return -reference_volume / bulk_modulus_pa;
}

namespace {

using Vec = std::array<double, 3>;

Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A quadratic face's shape functions N_a and their derivatives by s and t at the points of a rule
// exact for det[x, x_s, x_t], with the weights (reference area included) over 3.
struct FaceRule {
  unsigned int points = 0;
  double weight[9];                  // w_q / 3
  double n[9][9], ns[9][9], nt[9][9];  // [point][node]
};

// P2 triangle: vertices N = l (2 l - 1), edge nodes N = 4 l_i l_j, l = (1 - s - t, s, t).
FaceRule triangle_rule() {
  FaceRule r;
  // Dunavant's 6-point rule of degree 4: weights (of a unit area) and barycentric points.
  const double a = 0.445948490915965, wa = 0.223381589678011, b = 0.091576213509771, wb = 0.109951743655322;
  const double pts[6][2] = {{a, a}, {1 - 2 * a, a}, {a, 1 - 2 * a}, {b, b}, {1 - 2 * b, b}, {b, 1 - 2 * b}};
  r.points = 6;
  for (int q = 0; q < 6; ++q) {
    const double s = pts[q][0], t = pts[q][1];
    r.weight[q] = (q < 3 ? wa : wb) / 2 / 3;  // the reference triangle's area is 1/2
    const double l[3] = {1 - s - t, s, t}, ls[3] = {-1, 1, 0}, lt[3] = {-1, 0, 1};
    for (int v = 0; v < 3; ++v) {
      r.n[q][v] = l[v] * (2 * l[v] - 1);
      r.ns[q][v] = (4 * l[v] - 1) * ls[v];
      r.nt[q][v] = (4 * l[v] - 1) * lt[v];
    }
    const int edge[3][2] = {{0, 1}, {1, 2}, {2, 0}};
    for (int e = 0; e < 3; ++e) {
      const int i = edge[e][0], j = edge[e][1];
      r.n[q][3 + e] = 4 * l[i] * l[j];
      r.ns[q][3 + e] = 4 * (ls[i] * l[j] + l[i] * ls[j]);
      r.nt[q][3 + e] = 4 * (lt[i] * l[j] + l[i] * lt[j]);
    }
  }
  return r;
}

// Q2 quadrilateral: products of the 1D quadratics through 0, 1/2, 1, with 3 x 3 Gauss points.
FaceRule quadrilateral_rule() {
  const auto phi = [](int k, double x) { return k == 0 ? (2 * x - 1) * (x - 1) : k == 1 ? 4 * x * (1 - x) : x * (2 * x - 1); };
  const auto dphi = [](int k, double x) { return k == 0 ? 4 * x - 3 : k == 1 ? 4 - 8 * x : 4 * x - 1; };
  // Each node's 1D indices (0: s or t = 0, 1: 1/2, 2: 1) in the order of QuadraticFace.
  const int node[9][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}, {1, 1}};
  const double g = std::sqrt(0.6) / 2, x[3] = {0.5 - g, 0.5, 0.5 + g}, w[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
  FaceRule r;
  r.points = 9;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int q = 3 * i + j;
      r.weight[q] = w[i] * w[j] / 3;
      for (int a = 0; a < 9; ++a) {
        const int ks = node[a][0], kt = node[a][1];
        r.n[q][a] = phi(ks, x[i]) * phi(kt, x[j]);
        r.ns[q][a] = dphi(ks, x[i]) * phi(kt, x[j]);
        r.nt[q][a] = phi(ks, x[i]) * dphi(kt, x[j]);
      }
    }
  return r;
}

const FaceRule& rule(const CavityWall::QuadraticFace& f) {
  static const FaceRule triangle = triangle_rule(), quadrilateral = quadrilateral_rule();
  return f.nodes == 6 ? triangle : quadrilateral;
}

// x, dx/ds and dx/dt at point q of the deformed face.
struct FacePoint {
  Vec x{}, xs{}, xt{};
};
FacePoint at_point(const CavityWall::QuadraticFace& f, const FaceRule& r, unsigned int q, const double* u) {
  FacePoint p;
  for (unsigned int a = 0; a < f.nodes; ++a)
    for (int d = 0; d < 3; ++d) {
      const double x = f.position[a][d] + u[f.dofs[a][d]];
      p.x[d] += r.n[q][a] * x;
      p.xs[d] += r.ns[q][a] * x;
      p.xt[d] += r.nt[q][a] * x;
    }
  return p;
}

}  // namespace

double CavityWall::volume(const double* u) const {
  double v = 0;
  for (const Triangle& t : triangles) {
    const auto x = t.deformed(u);
    const auto bc = cross(x[1], x[2]);
    v += x[0][0] * bc[0] + x[0][1] * bc[1] + x[0][2] * bc[2];
  }
  v /= 6;
  for (const QuadraticFace& f : quadratic_faces) {
    const FaceRule& r = rule(f);
    for (unsigned int q = 0; q < r.points; ++q) {
      const FacePoint p = at_point(f, r, q, u);
      v += r.weight[q] * dot(p.x, cross(p.xs, p.xt));
    }
  }
  return v;
}

void CavityWall::add_gradient(const double* u, double scale, double* g) const {
  // dV/da = (b x c)/6, dV/db = (c x a)/6, dV/dc = (a x b)/6.
  for (const Triangle& t : triangles) {
    const auto x = t.deformed(u);
    for (int v = 0; v < 3; ++v) {
      const auto d = cross(x[(v + 1) % 3], x[(v + 2) % 3]);
      for (int c = 0; c < 3; ++c) g[t.dofs[v][c]] += scale * d[c] / 6;
    }
  }
  // det[x, x_s, x_t] is linear in each slot: dV/du_a = N_a (x_s x x_t) + N_a,s (x_t x x) + N_a,t (x x x_s).
  for (const QuadraticFace& f : quadratic_faces) {
    const FaceRule& r = rule(f);
    for (unsigned int q = 0; q < r.points; ++q) {
      const FacePoint p = at_point(f, r, q, u);
      const Vec s_t = cross(p.xs, p.xt), t_x = cross(p.xt, p.x), x_s = cross(p.x, p.xs);
      for (unsigned int a = 0; a < f.nodes; ++a)
        for (int c = 0; c < 3; ++c)
          g[f.dofs[a][c]] += scale * r.weight[q] * (r.n[q][a] * s_t[c] + r.ns[q][a] * t_x[c] + r.nt[q][a] * x_s[c]);
    }
  }
}

// The second derivative of det[x, x_s, x_t] by u_a,i and u_b,j takes two of its three slots:
// e_ijk [(N_a N_b,s - N_a,s N_b) x_t + (N_a,t N_b - N_a N_b,t) x_s + (N_a,s N_b,t - N_a,t N_b,s) x]_k.
void CavityWall::pair_couplings(const QuadraticFace& f, const double* u, std::array<std::array<double, 3>, 36>& c) {
  const FaceRule& r = rule(f);
  for (auto& v : c) v = {0, 0, 0};
  for (unsigned int q = 0; q < r.points; ++q) {
    const FacePoint p = at_point(f, r, q, u);
    const double* n = r.n[q];
    const double* ns = r.ns[q];
    const double* nt = r.nt[q];
    std::size_t k = 0;
    for (unsigned int a = 0; a < f.nodes; ++a)
      for (unsigned int b = a + 1; b < f.nodes; ++b, ++k) {
        const double ct = n[a] * ns[b] - ns[a] * n[b], cs = nt[a] * n[b] - n[a] * nt[b], cx = ns[a] * nt[b] - nt[a] * ns[b];
        for (int d = 0; d < 3; ++d) c[k][d] += r.weight[q] * (ct * p.xt[d] + cs * p.xs[d] + cx * p.x[d]);
      }
  }
}

}  // namespace fetouch::fem
