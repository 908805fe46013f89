// A cavity given by the regions it holds (amniotic fluid and a fetus meshed as solids) against the
// same cavity given by its surface: a box-shaped wall 1 cm thick around a cubic hole, pressed on
// top and held at its base.
// - Hollow: the hole's faces are a boundary region, the cavity is that surface (cavity_term.h).
// - Filled: the hole is meshed as a region of a material 10^5 times softer than the wall, and the
//   cavity is that region. Its wall is then the region's interface with the wall, an interior
//   surface; the pressure and the displacements must be the hollow model's (the filling adds only
//   its tiny stiffness), and the reference volume the hole's exactly.
// - Filled with a stiff inclusion in the fluid (a fetus): the cavity holds both regions, the law
//   still holds for their total volume (dV/V0 = -p/K).
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <utility>

#include "fem/cavity.h"
#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

constexpr double kCell = 0.01;  // the box is 5 cm wide, the hole the middle 3 cm
constexpr unsigned int kWall = 0, kFluid = 1, kInclusion = 2;
constexpr unsigned int kBase = 1, kHole = 2;

bool in_hole(const Point<3>& p) {
  for (int d = 0; d < 3; ++d)
    if (std::abs(p[d]) > 1.5 * kCell + 1e-9) return false;
  return true;
}

// The box [-2.5, 2.5]^3 cm of tetrahedra (each of 10^3 cubes, or 5^3, split in 24 by deal.II); hollow:
// without the hole's cells; otherwise the hole's cells are fluid (and the middle cube's the
// inclusion when asked). Tetrahedra: P1 faces are flat, so both cavities are the same triangles.
void box(dealii::Triangulation<3>& tria, bool hollow, bool inclusion, unsigned int divisions = 10) {
  dealii::Triangulation<3> cubes;
  dealii::GridGenerator::subdivided_hyper_cube(cubes, divisions, -2.5 * kCell, 2.5 * kCell);
  if (hollow) {  // removed before the split: deal.II 9.4 removes no tetrahedra
    std::set<dealii::Triangulation<3>::active_cell_iterator> hole;
    for (const auto& cell : cubes.active_cell_iterators())
      if (in_hole(cell->center())) hole.insert(cell);
    dealii::Triangulation<3> holed;
    dealii::GridGenerator::create_triangulation_with_removed_cells(cubes, hole, holed);
    dealii::GridGenerator::convert_hypercube_to_simplex_mesh(holed, tria);
  } else {
    dealii::GridGenerator::convert_hypercube_to_simplex_mesh(cubes, tria);
    for (const auto& cell : tria.active_cell_iterators()) {
      cell->set_material_id(in_hole(cell->center()) ? kFluid : kWall);
      if (inclusion && in_hole(cell->center() * 3.0)) cell->set_material_id(kInclusion);  // the middle 1 cm
    }
  }
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const Point<3> c = cell->face(f)->center();
      cell->face(f)->set_boundary_id(c[2] < -2.49 * kCell ? kBase : in_hole(c) ? kHole : 0);
    }
}

struct Answer {
  double reference_volume, pressure, volume_change, top_uz, side_ux;
};

Answer press(bool hollow, bool inclusion = false, int degree = 1) {
  dealii::Triangulation<3> tria;
  box(tria, hollow, inclusion, degree == 1 ? 10 : 5);  // P2 on cubes of 1 cm: fewer DOFs than P1's
  const double wall_e = 5000, nu = 0.4;
  const NeoHookean wall(lame_lambda(wall_e, nu), lame_mu(wall_e, nu));
  const NeoHookean fluid(lame_lambda(wall_e * 1e-5, 0.3), lame_mu(wall_e * 1e-5, 0.3));
  const NeoHookean stiff(lame_lambda(100 * wall_e, nu), lame_mu(100 * wall_e, nu));
  QuasiStaticSolver solver(tria, wall, degree);
  solver.prescribe_displacement(kBase, {true, true, true}, Tensor<1, 3>());
  CavityLaw water;
  water.bulk_modulus_pa = 2.2e9;
  if (hollow) {
    solver.add_cavity(kHole, water);
  } else {
    solver.set_region_material(kFluid, fluid);
    if (inclusion) solver.set_region_material(kInclusion, stiff);
    solver.add_cavity(inclusion ? std::set<unsigned int>{kFluid, kInclusion} : std::set<unsigned int>{kFluid}, water);
  }
  // A radius below the wall's thickness: the hollow box's patch must not reach the hole's faces.
  const int probe = solver.add_contact_patch(Point<3>(0, 0, 2.5 * kCell), 0.008);
  Tensor<1, 3> force;
  force[2] = -0.2;
  solver.set_patch_force(probe, force);
  NewtonSettings settings;
  settings.load_steps = 2;
  const SolveReport report = solver.solve(settings);
  if (!report.converged) throw std::runtime_error("pressed box: " + report.failure);
  const Answer a{solver.cavity_reference_volume(), solver.cavity_pressure(),
                 solver.cavity_volume() / solver.cavity_reference_volume() - 1,
                 solver.displacement_at(Point<3>(0, 0, 2.5 * kCell))[2],
                 solver.displacement_at(Point<3>(2.5 * kCell, 0, 0.5 * kCell))[0]};
  std::printf("P%d, %s: V0 %.6e m^3, p %.4f Pa, dV/V0 %.3e, top u_z %.4e m, side u_x %.4e m\n",
              degree, hollow ? "hollow" : inclusion ? "filled, with an inclusion" : "filled", a.reference_volume, a.pressure,
              a.volume_change, a.top_uz, a.side_ux);
  return a;
}

// Both reference volumes the hole's; the press raises the pressure and the side bulges out (the
// water's volume is kept); filled and hollow agree to 1e-4; the liquid's law dV/V0 = -p/K holds to
// its own convergence test (1e-10 V0) and Newton's.
void expect_filled_as_hollow(const Answer& hollow, const Answer& filled) {
  const double hole = std::pow(3 * kCell, 3);
  EXPECT_NEAR(hollow.reference_volume, hole, 1e-12 * hole);
  EXPECT_NEAR(filled.reference_volume, hole, 1e-12 * hole);
  ASSERT_GT(hollow.pressure, 1.0);
  EXPECT_GT(hollow.side_ux, 0);
  EXPECT_NEAR(filled.pressure, hollow.pressure, 1e-4 * hollow.pressure);
  EXPECT_NEAR(filled.top_uz, hollow.top_uz, 1e-4 * std::abs(hollow.top_uz));
  EXPECT_NEAR(filled.side_ux, hollow.side_ux, 1e-4 * std::abs(hollow.side_ux));
  EXPECT_NEAR(filled.volume_change, -filled.pressure / 2.2e9, 1e-9);
}

TEST(CavityRegions, AFilledRegionBehavesAsTheHollowCavity) { expect_filled_as_hollow(press(true), press(false)); }

// P2 (the default scene's regions with quadratic tetrahedra, on cubes of 1 cm): the wall is the
// interface's curved faces, and the same equivalence holds; the liquid's law holds for the curved
// volume.
TEST(CavityRegions, QuadraticElementsFilledBehaveAsHollowToo) {
  expect_filled_as_hollow(press(true, false, 2), press(false, false, 2));
}

TEST(CavityRegions, AStiffInclusionInTheFluidKeepsTheTotalVolume) {
  const Answer with = press(false, true), without = press(false);
  EXPECT_NEAR(with.reference_volume, without.reference_volume, 1e-12 * without.reference_volume);
  EXPECT_NEAR(with.volume_change, -with.pressure / 2.2e9, 1e-9);
  // A floating inclusion changes little: the fluid's pressure carries the load either way.
  EXPECT_NEAR(with.pressure, without.pressure, 0.05 * without.pressure);
}

// Haptic frames on the filled box, the press growing from 0.2 N by 5 % and by 50 %. A frame starts
// from the compliance's linear prediction, and every Newton step is linear too: both miss the
// water's volume to second order, and water's stiffness (K/V0 ~ 10^14 Pa/m^3) turns that miss into
// newtons on the wall. Unrestored, the small frame needed three iterations (the accuracy policy
// waited for the volume law's own 1e-10 V0) and the large one stalled: each full step raised the
// residual, the line search shrank it to nothing: 59 iterations and a load-step cut. Restoring
// the volume along a pressure's own deformation after each move, and weighing the volume law in
// the policy, the small frame is accurate after one iteration and the large one converges without
// a cut; both end where a tight static solve does, to the policy's tolerances.
struct FrameResult {
  SolveReport report;
  Tensor<1, 3> u;
  double pressure;
};

FrameResult pressed_box(double fz, const NewtonSettings& settings, bool frame) {
  dealii::Triangulation<3> tria;
  box(tria, false, false);
  const double wall_e = 5000, nu = 0.4;
  const NeoHookean wall(lame_lambda(wall_e, nu), lame_mu(wall_e, nu));
  const NeoHookean fluid(lame_lambda(wall_e * 1e-5, 0.3), lame_mu(wall_e * 1e-5, 0.3));
  QuasiStaticSolver solver(tria, wall, 1);
  solver.prescribe_displacement(kBase, {true, true, true}, Tensor<1, 3>());
  solver.set_region_material(kFluid, fluid);
  CavityLaw water;
  water.bulk_modulus_pa = 2.2e9;
  solver.add_cavity(std::set<unsigned int>{kFluid}, water);
  const int probe = solver.add_contact_patch(Point<3>(0, 0, 2.5 * kCell), 0.008);
  Tensor<1, 3> force;
  force[2] = frame ? -0.2 : fz;
  solver.set_patch_force(probe, force);
  NewtonSettings first = settings;
  first.load_steps = 2;
  FrameResult out;
  out.report = solver.solve(first);
  if (frame) {
    EXPECT_TRUE(out.report.converged);
    solver.compliance();
    force[2] = fz;
    solver.set_patch_force(probe, force);
    out.report = solver.solve(settings);
  }
  out.u = solver.patch_displacement(probe);
  out.pressure = solver.cavity_pressure();
  return out;
}

TEST(CavityRegions, FramesOnTheLiquidNeitherStallNorOverwork) {
  NewtonSettings policy;
  policy.position_tolerance_m = 1e-5;
  policy.force_tolerance_n = 1e-3;
  NewtonSettings tight;
  tight.relative_tolerance = 1e-12;
  for (const double fz : {-0.21, -0.3}) {
    const FrameResult frame = pressed_box(fz, policy, true), reference = pressed_box(fz, tight, false);
    ASSERT_TRUE(frame.report.converged && reference.report.converged);
    std::printf("press %.2f N: %d Newton iteration(s), %d cut(s), patch off by %.3e m, pressure %.4f against %.4f Pa\n",
                -fz, frame.report.total_iterations, frame.report.cuts, (frame.u - reference.u).norm(), frame.pressure,
                reference.pressure);
    EXPECT_EQ(frame.report.cuts, 0);
    EXPECT_LE(frame.report.total_iterations, fz > -0.25 ? 1 : 6);
    if (fz > -0.25) {
      EXPECT_TRUE(frame.report.steps.back().accurate);
    }
    EXPECT_LT((frame.u - reference.u).norm(), 1e-5);
    EXPECT_NEAR(frame.pressure, reference.pressure, 0.01 * reference.pressure);
  }
}

TEST(CavityRegions, RegionsThatAreNothingOrEverythingAreRefused) {
  dealii::Triangulation<3> tria;
  box(tria, false, false);
  const NeoHookean wall(lame_lambda(5000, 0.4), lame_mu(5000, 0.4));
  QuasiStaticSolver none(tria, wall, 1);
  EXPECT_THROW(none.add_cavity(std::set<unsigned int>{7}, CavityLaw{}), std::invalid_argument);
  QuasiStaticSolver all(tria, wall, 1);
  EXPECT_THROW(all.add_cavity(std::set<unsigned int>{kWall, kFluid}, CavityLaw{}), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::fem
