// A fluid-filled cavity (an amniotic sac, a water balloon): a closed inner surface of the tissue
// enclosing fluid whose pressure follows its volume, so that pressing one side raises the pressure
// everywhere on the wall.
//
// The wall is the mesh's boundary faces of one region, oriented so that their normals point out of
// the cavity (into the tissue). Linear elements' faces are flat triangles between the vertices (P1
// faces exactly; a Q1 face split along a diagonal), and the enclosed volume of the deformed wall is
// exactly
//   V(u) = 1/6 sum over triangles of a . (b x c),   a, b, c = X + u at the vertices.
// Quadratic elements' faces are curved: x(s, t) = sum_a N_a(s, t) (X_a + u_a) through the face's
// nodes (a P2 triangle's 6, a Q2 quadrilateral's 9), and by the divergence theorem
//   V(u) = 1/3 sum over faces of the integral of det[x, dx/ds, dx/dt] ds dt,
// a polynomial of degree 4 (P2) or 5 in each of s, t (Q2), integrated exactly by a 6-point rule
// (Dunavant's of degree 4) or 3 x 3 Gauss points. Either way V has the gradient g = dV/du and a
// sparse Hessian coupling the nodes of each face. The fluid
// stores the energy Pi(V) with p = -dPi/dV:
//   linear (a liquid):    p = p0 - K (V - V0) / V0       Pi = -p0 V + K (V - V0)^2 / (2 V0)
//   isothermal gas:       p = p0 V0 / V                   Pi = -p0 V0 ln V
// The solver takes p as an unknown beside u, with the law's residual V(u) - V_law(p) = 0: the wall
// carries the load p g, the tangent gains -p d2V/du2 (sparse), and eliminating dp adds
// (-dp/dV) g g' (dense, rank one; applied by the Sherman-Morrison formula).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace fetouch::fem {

struct CavityLaw {
  bool gas = false;             // false: linear (liquid)
  double initial_pressure_pa = 0;
  double bulk_modulus_pa = 2.2e9;  // linear law only (water)
  double pressure(double volume, double reference_volume) const;
  // The law inverted, V_law(p), and dV_law/dp (< 0): the solver takes p as an unknown.
  double volume(double pressure, double reference_volume) const;
  double volume_derivative(double pressure, double reference_volume) const;
};

struct CavityWall {
  struct Triangle {
    std::array<std::array<unsigned int, 3>, 3> dofs;  // [vertex][component] global dof index
    std::array<std::array<double, 3>, 3> position;    // [vertex] reference position, m
    // The vertices at displacement u: position + u.
    std::array<std::array<double, 3>, 3> deformed(const double* u) const {
      std::array<std::array<double, 3>, 3> x;
      for (int v = 0; v < 3; ++v)
        for (int d = 0; d < 3; ++d) x[v][d] = position[v][d] + u[dofs[v][d]];
      return x;
    }
  };
  std::vector<Triangle> triangles;

  // A quadratic element's face: a triangle's vertices (s, t) = (0, 0), (1, 0), (0, 1), then its edge
  // nodes 01, 12, 20; or a quadrilateral's corners (0, 0), (1, 0), (1, 1), (0, 1) in turn, its edge
  // nodes 01, 12, 23, 30 and its centre. dx/ds x dx/dt points out of the cavity.
  struct QuadraticFace {
    unsigned int nodes = 6;  // 6: P2 triangle, 9: Q2 quadrilateral
    std::array<std::array<unsigned int, 3>, 9> dofs;  // [node][component] global dof index
    std::array<std::array<double, 3>, 9> position;    // [node] reference position, m
  };
  std::vector<QuadraticFace> quadratic_faces;
  // For every pair of nodes a < b of `face`, in the order (0, 1), (0, 2), ..., (1, 2), ...: the vector
  // c_ab with d2V / du_a,i du_b,j = e_ijk c_ab,k (the flat triangle's c_ab is its third vertex / 6).
  static void pair_couplings(const QuadraticFace& face, const double* u, std::array<std::array<double, 3>, 36>& c);

  // V at displacement u (indexed by global dof).
  double volume(const double* u) const;
  // g += scale dV/du.
  void add_gradient(const double* u, double scale, double* g) const;
  // Calls add(row_dof, column_dof, scale d2V/du_row du_column) for every structurally non-zero
  // entry, in the same order for every u.
  template <class Add>
  void add_hessian(const double* u, double scale, Add add) const;
};

template <class Add>
void CavityWall::add_hessian(const double* u, double scale, Add add) const {
  // d2V/da_i db_j = 1/6 e_ijk c_k, and cyclically: (a, b, c) -> (b, c, a) -> (c, a, b).
  for (const Triangle& t : triangles) {
    const auto x = t.deformed(u);
    for (int v = 0; v < 3; ++v) {
      const int w = (v + 1) % 3, o = (v + 2) % 3;  // block (v, w) uses the third vertex o
      const std::array<double, 3>& c = x[o];
      const double block[3][3] = {{0, c[2], -c[1]}, {-c[2], 0, c[0]}, {c[1], -c[0], 0}};  // e_ijk c_k
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          if (i == j) continue;  // structurally zero (never by value: callers count the calls)
          const double value = scale * block[i][j] / 6;
          add(t.dofs[v][i], t.dofs[w][j], value);
          add(t.dofs[w][j], t.dofs[v][i], value);
        }
    }
  }
  std::array<std::array<double, 3>, 36> c;
  for (const QuadraticFace& f : quadratic_faces) {
    pair_couplings(f, u, c);
    std::size_t k = 0;
    for (unsigned int a = 0; a < f.nodes; ++a)
      for (unsigned int b = a + 1; b < f.nodes; ++b, ++k) {
        const std::array<double, 3>& v = c[k];
        const double block[3][3] = {{0, v[2], -v[1]}, {-v[2], 0, v[0]}, {v[1], -v[0], 0}};  // e_ijk c_k
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) {
            if (i == j) continue;
            const double value = scale * block[i][j];
            add(f.dofs[a][i], f.dofs[b][j], value);
            add(f.dofs[b][j], f.dofs[a][i], value);
          }
      }
  }
}

}  // namespace fetouch::fem
