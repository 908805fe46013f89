// The quasi-static solver against closed forms: patch tests (a homogeneous deformation is
// reproduced to round-off on distorted meshes, for P1, P2, Q1 and Q2, linear and nonlinear) and the
// homogeneous uniaxial stretch of neo-Hookean and Mooney-Rivlin blocks.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

// A box [0, a] x [0, b] x [0, c] of n[0] x n[1] x n[2] bricks, with boundary ids 0..5 = x-, x+, y-,
// y+, z-, z+.
void make_box(dealii::Triangulation<3>& tria, bool simplex, std::vector<unsigned int> n, Point<3> size) {
  const Point<3> origin(0, 0, 0);
  if (simplex) {
    dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, n, origin, size);
    for (const auto& cell : tria.active_cell_iterators())
      for (const unsigned int f : cell->face_indices()) {
        if (!cell->face(f)->at_boundary()) continue;
        const Point<3> c = cell->face(f)->center();
        for (int d = 0; d < 3; ++d) {
          if (std::abs(c[d]) < 1e-12) cell->face(f)->set_boundary_id(2 * d);
          if (std::abs(c[d] - size[d]) < 1e-12) cell->face(f)->set_boundary_id(2 * d + 1);
        }
      }
  } else {
    dealii::GridGenerator::subdivided_hyper_rectangle(tria, n, origin, size, /*colorize=*/true);
  }
}
void make_box(dealii::Triangulation<3>& tria, bool simplex, unsigned int n, Point<3> size) {
  make_box(tria, simplex, {n, n, n}, size);
}

struct Element {
  bool simplex;
  int degree;
  const char* name;
};
const Element kElements[] = {{true, 1, "P1"}, {true, 2, "P2"}, {false, 1, "Q1"}, {false, 2, "Q2"}};

// u = G x on the whole boundary of a randomly distorted mesh: the discrete solution is G x at every
// node, because a homogeneous F satisfies equilibrium exactly and lies in every element's space.
// Linear elasticity (one linear solve) and neo-Hookean at 20 % strain (Newton).
TEST(QuasiStatic, PatchTestOnDistortedMeshes) {
  Tensor<2, 3> g;
  g[0][0] = 0.12, g[0][1] = -0.05, g[1][1] = -0.08, g[1][2] = 0.07, g[2][0] = 0.04, g[2][2] = 0.2;
  const auto exact = [&](const Point<3>& x) { return Tensor<1, 3>(g * x); };
  const LinearElastic linear(lame_lambda(5000, 0.3), lame_mu(5000, 0.3));
  const NeoHookean neo(lame_lambda(5000, 0.3), lame_mu(5000, 0.3));
  for (const Element& e : kElements)
    for (const Material* material : {static_cast<const Material*>(&linear), static_cast<const Material*>(&neo)}) {
      dealii::Triangulation<3> tria;
      make_box(tria, e.simplex, 3, Point<3>(0.1, 0.08, 0.06));
      dealii::GridTools::distort_random(0.25, tria, /*keep_boundary=*/true, /*seed=*/5);
      QuasiStaticSolver solver(tria, *material, e.degree);
      for (unsigned int b = 0; b < 6; ++b) solver.prescribe_displacement(b, {true, true, true}, exact);
      NewtonSettings settings;
      settings.relative_tolerance = 1e-13;
      settings.absolute_tolerance = 1e-13;
      const SolveReport report = solver.solve(settings);
      ASSERT_TRUE(report.converged) << e.name << " " << material->name() << ": " << report.failure;
      // Round-off of a few solves, against displacements of order 0.01 m.
      EXPECT_LT(solver.max_nodal_error(exact), 1e-12) << e.name << " " << material->name();
    }
}

// Cauchy stress of an isotropic psi(I1, I2, J), written out for a diagonal stretch: with
// b = diag(l1^2, l2^2, l2^2),  sigma = 2/J [(psi_1 + I1 psi_2) b - psi_2 b^2] + psi_J I,
// and P11 = J sigma11 / l1. psi's partial derivatives are those of each model's formula.
struct Derivs {
  double d1, d2, dj;
};
double axial_and_lateral(const std::function<Derivs(double, double, double)>& psi, double l1, double l2,
                         double& lateral_cauchy) {
  const double b1 = l1 * l1, b2 = l2 * l2, i1 = b1 + 2 * b2, i2 = 2 * b1 * b2 + b2 * b2, j = l1 * l2 * l2;
  const Derivs d = psi(i1, i2, j);
  const auto sigma = [&](double bb) { return 2 / j * ((d.d1 + i1 * d.d2) * bb - d.d2 * bb * bb) + d.dj; };
  lateral_cauchy = sigma(b2);
  return j * sigma(b1) / l1;
}

// The lateral stretch with zero lateral stress, by bisection on [0.3, 1.5].
double lateral_stretch(const std::function<Derivs(double, double, double)>& psi, double l1) {
  double low = 0.3, high = 1.5, s;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (low + high);
    axial_and_lateral(psi, l1, mid, s);
    (s > 0 ? high : low) = mid;  // lateral tension: too wide
  }
  return 0.5 * (low + high);
}

// A unit cube stretched to l1 = 1.35 along x with symmetry supports (x-: u_x = 0, y-: u_y = 0,
// z-: u_z = 0) and free lateral faces: the deformation is homogeneous, so the force on x+ equals
// P11 and the lateral displacement (l2 - 1), to 1e-8 relative.
TEST(QuasiStatic, UniaxialStretchMatchesTheClosedForms) {
  const double e = 5000, nu = 0.3, mu = lame_mu(e, nu), lambda = lame_lambda(e, nu), kappa = 4 * mu;
  const double c10 = 0.3 * mu, c01 = 0.2 * mu, l1 = 1.35;
  const NeoHookean neo(lambda, mu);
  const MooneyRivlin mooney(c10, c01, kappa);
  const std::function<Derivs(double, double, double)> neo_psi = [&](double, double, double j) {
    return Derivs{mu / 2, 0, (-mu + lambda * std::log(j)) / j};
  };
  const std::function<Derivs(double, double, double)> mooney_psi = [&](double i1, double i2, double j) {
    const double j23 = std::pow(j, -2.0 / 3), j43 = j23 * j23;
    return Derivs{c10 * j23, c01 * j43,
                  -2.0 / 3 * c10 * j23 / j * i1 - 4.0 / 3 * c01 * j43 / j * i2 + kappa / 2 * (j - 1 / j)};
  };
  const std::pair<const Material*, const std::function<Derivs(double, double, double)>*> cases[] = {
      {&neo, &neo_psi}, {&mooney, &mooney_psi}};
  for (const auto& [material, psi] : cases)
    for (const Element& el : {kElements[0], kElements[3]}) {
      dealii::Triangulation<3> tria;
      make_box(tria, el.simplex, 2, Point<3>(1, 1, 1));
      QuasiStaticSolver solver(tria, *material, el.degree);
      solver.prescribe_displacement(0, {true, false, false}, Tensor<1, 3>());
      solver.prescribe_displacement(2, {false, true, false}, Tensor<1, 3>());
      solver.prescribe_displacement(4, {false, false, true}, Tensor<1, 3>());
      Tensor<1, 3> pull;
      pull[0] = l1 - 1;
      solver.prescribe_displacement(1, {true, false, false}, pull);
      NewtonSettings settings;
      settings.load_steps = 3;
      settings.relative_tolerance = 1e-13;
      settings.absolute_tolerance = 1e-10;
      const SolveReport report = solver.solve(settings);
      ASSERT_TRUE(report.converged) << material->name() << " " << el.name << ": " << report.failure;
      const double l2 = lateral_stretch(*psi, l1);
      double lateral;
      const double p11 = axial_and_lateral(*psi, l1, l2, lateral);
      std::printf("%s %s: P11 %.12g force %.12g l2 %.10f corner %.10f iterations %d dofs %u\n", material->name().c_str(), el.name, p11, solver.boundary_force(1)[0], l2, solver.displacement_at(Point<3>(1, 1, 1))[1], report.total_iterations, solver.dofs());
      EXPECT_NEAR(solver.boundary_force(1)[0], p11, 1e-8 * std::abs(p11)) << material->name() << " " << el.name;
      const Tensor<1, 3> corner = solver.displacement_at(Point<3>(1, 1, 1));
      EXPECT_NEAR(corner[1], l2 - 1, 1e-8 * std::abs(l2 - 1)) << material->name() << " " << el.name;
      EXPECT_NEAR(corner[2], l2 - 1, 1e-8 * std::abs(l2 - 1)) << material->name() << " " << el.name;
      // Newton converges quadratically: a handful of iterations per step.
      EXPECT_LE(report.total_iterations, 3 * 8) << material->name();
    }
}

}  // namespace
}  // namespace fetouch::fem

namespace fetouch::fem {
namespace {

// Manufactured solution for linear elasticity on the unit cube: u = a s(x), s = sin(pi x) sin(pi y)
// sin(pi z) (zero on the boundary), body force f = -div sigma = 3 pi^2 mu a s - (lambda + mu)
// grad(div u), with d_i d_j s = pi^2 cos(pi x_i) cos(pi x_j) sin(pi x_k) (i != j), -pi^2 s (i = j).
// The L2 error must fall as h^(p+1): slope 2 for P1/Q1, 3 for P2/Q2, within 0.2, fitted on the
// two finest of three meshes (the coarsest is pre-asymptotic for P1).
TEST(QuasiStatic, ManufacturedSolutionConvergesAtTheOptimalOrder) {
  const double mu = lame_mu(5000, 0.3), lambda = lame_lambda(5000, 0.3), pi = M_PI;
  const Tensor<1, 3> a = [] {
    Tensor<1, 3> t;
    t[0] = 1e-3, t[1] = 2e-3, t[2] = -1.5e-3;
    return t;
  }();
  const auto exact = [&](const Point<3>& x) {
    return Tensor<1, 3>(a * (std::sin(pi * x[0]) * std::sin(pi * x[1]) * std::sin(pi * x[2])));
  };
  const auto body_force = [&](const Point<3>& x) {
    double s[3], c[3];
    for (int d = 0; d < 3; ++d) s[d] = std::sin(pi * x[d]), c[d] = std::cos(pi * x[d]);
    const double product = s[0] * s[1] * s[2];
    Tensor<1, 3> f;
    for (int i = 0; i < 3; ++i) {
      double grad_div = 0;
      for (int j = 0; j < 3; ++j) {
        const int k = 3 - i - j;
        grad_div += a[j] * (i == j ? -pi * pi * product : pi * pi * c[i] * c[j] * s[k]);
      }
      f[i] = 3 * pi * pi * mu * a[i] * product - (lambda + mu) * grad_div;
    }
    return f;
  };
  const LinearElastic material(lambda, mu);
  for (const Element& e : kElements) {
    std::vector<double> h, error;
    for (unsigned int n : {2u, 4u, 8u}) {
      dealii::Triangulation<3> tria;
      make_box(tria, e.simplex, n, Point<3>(1, 1, 1));
      QuasiStaticSolver solver(tria, material, e.degree);
      for (unsigned int b = 0; b < 6; ++b) solver.prescribe_displacement(b, {true, true, true}, Tensor<1, 3>());
      solver.apply_body_force(body_force);
      ASSERT_TRUE(solver.solve({}).converged);
      h.push_back(1.0 / n);
      error.push_back(solver.l2_error(exact));
    }
    const double slope = std::log(error[1] / error[2]) / std::log(h[1] / h[2]);
    std::printf("%s: L2 errors %.3e %.3e %.3e at h = 1/2, 1/4, 1/8; fitted order %.2f\n", e.name, error[0], error[1],
                error[2], slope);
    EXPECT_NEAR(slope, e.degree + 1, 0.2) << e.name;
  }
}

}  // namespace
}  // namespace fetouch::fem

namespace fetouch::fem {
namespace {

// The elasticity assembly on one thread takes the two threads' groups in turn (elasticity_term.h),
// so a solve gives the same answer to the bit on one thread or two: a neo-Hookean block squeezed by
// 20 % and sheared. A cube of 2,560 tetrahedra (over the 2,000 at which a second thread starts; the
// 640 cells along the cut go to one thread after both halves), and a slab of 5,120 cut across its
// length, whose 2,560 cells along the cut are cut again.
struct AssemblyBlock {
  std::vector<unsigned int> bricks;
  Point<3> size;
};
class AssemblyThreads : public ::testing::TestWithParam<AssemblyBlock> {};
TEST_P(AssemblyThreads, OneAssemblyThreadOrTwoGiveTheSameAnswerToTheBit) {
  const AssemblyBlock block = GetParam();
  const NeoHookean neo(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  struct Answer {
    Tensor<1, 3> force, inside, corner;
  };
  const auto solve_with = [&](unsigned int threads) {
    dealii::Triangulation<3> tria;
    make_box(tria, true, block.bricks, block.size);
    dealii::GridTools::distort_random(0.2, tria, /*keep_boundary=*/true, /*seed=*/3);
    QuasiStaticSolver solver(tria, neo, 1);
    solver.set_assembly_threads(threads);
    solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
    Tensor<1, 3> top;
    top[0] = 0.006, top[2] = -0.01;
    solver.prescribe_displacement(5, {true, true, true}, top);
    NewtonSettings settings;
    settings.load_steps = 2;
    const SolveReport report = solver.solve(settings);
    EXPECT_TRUE(report.converged) << report.failure;
    EXPECT_GT(report.total_iterations, 4);  // a nonlinear solve: many assemblies, each summed anew
    return Answer{solver.boundary_force(5), solver.displacement_at(Point<3>(0.031, 0.047, 0.023)),
                  solver.displacement_at(Point<3>(0.08, 0, 0.025))};
  };
  const Answer one = solve_with(1), two = solve_with(2);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(one.force[c], two.force[c]) << c;
    EXPECT_EQ(one.inside[c], two.inside[c]) << c;
    EXPECT_EQ(one.corner[c], two.corner[c]) << c;
  }
  EXPECT_GT(std::abs(one.force[2]), 1.0);  // N: the squeeze carries a load
}
INSTANTIATE_TEST_SUITE_P(QuasiStatic, AssemblyThreads,
                         ::testing::Values(AssemblyBlock{{8, 8, 8}, Point<3>(0.08, 0.08, 0.05)},
                                           AssemblyBlock{{4, 16, 16}, Point<3>(0.1, 0.08, 0.05)}),
                         [](const ::testing::TestParamInfo<AssemblyBlock>& block) {
                           return block.index == 0 ? "Cube" : "Slab";
                         });

}  // namespace
}  // namespace fetouch::fem
