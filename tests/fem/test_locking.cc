// Volumetric locking: a nearly incompressible block (nu = 0.4999) clamped at its base and pressed by
// a uniform pressure on its top bulges sideways; its top sinks by an amount that a locking element
// underestimates many times over on a coarse mesh. The mean-dilatation formulation (a pressure
// constant per cell, condensed) on a coarse mesh must stay within 2 % of its own fine-mesh answer,
// while pure-displacement P1 tetrahedra on the same coarse mesh are shown to lock (they sink about
// half as far) and pure-displacement Q1 hexahedra lock completely (a few per cent).
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

constexpr double kSide = 0.05;  // m

void mark(dealii::Triangulation<3>& tria) {
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const double z = cell->face(f)->center()[2];
      cell->face(f)->set_boundary_id(std::abs(z) < 1e-12 ? 4 : std::abs(z - kSide) < 1e-12 ? 5 : 0);
    }
}

// The top centre's vertical displacement under a pressure of 2 % of the shear modulus.
double top_sink(const dealii::Triangulation<3>& tria, int degree, bool mean_dilatation, int* newton = nullptr) {
  const double youngs = 5000, nu = 0.4999;
  const NearlyIncompressibleNeoHookean material(youngs / (3 * (1 - 2 * nu)), lame_mu(youngs, nu));
  QuasiStaticSolver solver(tria, material, degree);
  solver.use_mean_dilatation(mean_dilatation);
  solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  Tensor<1, 3> traction;
  traction[2] = -0.02 * material.shear_modulus();
  solver.apply_traction(5, traction);
  NewtonSettings settings;
  settings.load_steps = 2;
  const SolveReport report = solver.solve(settings);
  if (!report.converged) throw std::runtime_error("the locking block did not converge: " + report.failure);
  if (newton) *newton = report.total_iterations;
  return -solver.displacement_at(Point<3>(kSide / 2, kSide / 2, kSide))[2];
}

TEST(Locking, MeanDilatationMatchesItsFineMeshAnswerWhereP1Locks) {
  dealii::Triangulation<3> coarse_hex, fine_hex, coarse_tet;
  dealii::GridGenerator::subdivided_hyper_cube(coarse_hex, 4, 0, kSide);
  dealii::GridGenerator::subdivided_hyper_cube(fine_hex, 12, 0, kSide);
  dealii::GridGenerator::subdivided_hyper_cube_with_simplices(coarse_tet, 4, 0, kSide);
  mark(coarse_hex), mark(fine_hex), mark(coarse_tet);
  int newton = 0;
  const double fine = top_sink(fine_hex, 1, true, &newton);
  const double coarse = top_sink(coarse_hex, 1, true);
  const double q1 = top_sink(coarse_hex, 1, false);
  const double p1 = top_sink(coarse_tet, 1, false);
  std::printf("top sink, m: Q1 mean dilatation 12^3 %.6e (%d Newton), 4^3 %.6e (%+.2f %%); "
              "4^3 pure displacement Q1 %.6e (%.1f %%), P1 %.6e (%.1f %%)\n",
              fine, newton, coarse, 100 * (coarse / fine - 1), q1, 100 * q1 / fine, p1, 100 * p1 / fine);
  EXPECT_GT(fine, 0.0);
  EXPECT_LT(std::abs(coarse / fine - 1), 0.02);
  EXPECT_LT(p1, 0.7 * fine) << "P1 at nu = 0.4999 should lock";
  EXPECT_LT(q1, coarse) << "pure-displacement Q1 is stiffer than mean dilatation";
}

TEST(Locking, MeanDilatationNeedsADecoupledMaterial) {
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_cube(tria, 1, 0, kSide);
  const NeoHookean coupled(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver(tria, coupled, 1);
  EXPECT_THROW(solver.use_mean_dilatation(true), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::fem
