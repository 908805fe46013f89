// The fluid-filled cavity against closed forms and physics:
// - Lame's thick-walled sphere: an octant of a shell (inner radius a, outer b, rollers on the three
//   symmetry planes) filled with a pre-pressurised liquid (p0, bulk modulus K) settles where the
//   wall's linear-elastic expansion u_r(a) = p C, C = a^3 [(1 - 2 nu) a + (1 + nu) b^3 / (2 a^2)] /
//   (E (b^3 - a^3)), and the liquid's law p = p0 - K dV / V0 with dV / V0 = 3 u_r(a) / a agree:
//   p = p0 / (1 + 3 K C / a).
// - Pressing one side of a water-filled sphere held at its equator raises the pressure, keeps the
//   water's volume (dV/V0 = -p/K) and bulges the far side out well beyond the empty sphere's sag.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/manifold_lib.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "fem/cavity.h"
#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

constexpr double kInner = 0.03, kOuter = 0.05;

void shell(dealii::Triangulation<3>& tria, bool octant, int refinements) {
  dealii::Triangulation<3> full;
  dealii::GridGenerator::hyper_shell(full, Point<3>(), kInner, kOuter, 6);
  full.refine_global(1);  // children's faces now lie on the coordinate planes
  if (octant) {
    std::set<dealii::Triangulation<3>::active_cell_iterator> outside;
    for (const auto& cell : full.active_cell_iterators())
      if (cell->center()[0] < 0 || cell->center()[1] < 0 || cell->center()[2] < 0) outside.insert(cell);
    dealii::GridGenerator::create_triangulation_with_removed_cells(full, outside, tria);
  } else {
    tria.copy_triangulation(full);
  }
  tria.set_all_manifold_ids(0);
  tria.set_manifold(0, dealii::SphericalManifold<3>(Point<3>()));
  tria.refine_global(refinements);
  // Boundary ids: 0 inner, 1 outer, 2 + d the symmetry plane x_d = 0.
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const Point<3> c = cell->face(f)->center();
      unsigned int id = c.norm() < (kInner + kOuter) / 2 ? 0 : 1;
      for (unsigned int d = 0; d < 3; ++d)
        if (octant && std::abs(c[d]) < 1e-9) id = 2 + d;
      cell->face(f)->set_boundary_id(id);
    }
}

struct LameAnswer {
  double pressure, expected_pressure, volume_change, expected_volume_change, u_inner, u_lame, u_outer, u_outer_lame;
};

LameAnswer pressurised_octant(int degree, int refinements) {
  dealii::Triangulation<3> tria;
  shell(tria, /*octant=*/true, refinements);
  const double youngs = 5000, nu = 0.3;
  const LinearElastic material(lame_lambda(youngs, nu), lame_mu(youngs, nu));
  QuasiStaticSolver solver(tria, material, degree);
  for (unsigned int d = 0; d < 3; ++d) {
    std::array<bool, 3> normal{false, false, false};
    normal[d] = true;
    solver.prescribe_displacement(2 + d, normal, Tensor<1, 3>());
  }
  const double a = kInner, b = kOuter;
  const double compliance = a * a * a * ((1 - 2 * nu) * a + (1 + nu) * b * b * b / (2 * a * a)) / (youngs * (b * b * b - a * a * a));
  CavityLaw law;
  law.initial_pressure_pa = 5;               // small against E: linear elasticity applies
  law.bulk_modulus_pa = a / (3 * compliance);  // the liquid as stiff as the wall: p halves
  solver.add_cavity(0, law);
  const double octant_volume = M_PI * a * a * a / 6;
  std::printf("P%d, %d refinements: reference cavity volume %.6e m^3, octant of the sphere %.6e m^3\n", degree, refinements,
              solver.cavity_reference_volume(), octant_volume);
  EXPECT_NEAR(solver.cavity_reference_volume(), octant_volume, 0.025 * octant_volume);  // faceted: 1.6 % less
  NewtonSettings settings;
  EXPECT_TRUE(solver.solve(settings).converged);
  LameAnswer r;
  r.expected_pressure = law.initial_pressure_pa / (1 + 3 * law.bulk_modulus_pa * compliance / a);
  r.pressure = solver.cavity_pressure();
  r.u_lame = r.expected_pressure * compliance;  // at the inner wall
  r.expected_volume_change = 3 * r.u_lame / a;
  r.volume_change = solver.cavity_volume() / solver.cavity_reference_volume() - 1;
  r.u_inner = solver.displacement_at(Point<3>(a, 0, 0))[0];
  r.u_outer = solver.displacement_at(Point<3>(b, 0, 0))[0];
  r.u_outer_lame = r.expected_pressure * a * a * a / (youngs * (b * b * b - a * a * a)) * ((1 - 2 * nu) * b + (1 + nu) * b / 2);
  std::printf("cavity pressure %.5f Pa (Lame %.5f Pa); dV/V0 %.5e (Lame 3 u_r(a)/a %.5e); u_r inner vertex %.4e m "
              "(Lame %.4e m), outer %.4e m (Lame %.4e m)\n",
              r.pressure, r.expected_pressure, r.volume_change, r.expected_volume_change, r.u_inner, r.u_lame, r.u_outer,
              r.u_outer_lame);
  return r;
}

// Pressure and volume within 1 %, the outer wall within 3 %, the inner wall within `inner`.
void expect_lame(const LameAnswer& r, double inner) {
  EXPECT_NEAR(r.pressure, r.expected_pressure, 0.01 * r.expected_pressure);
  EXPECT_NEAR(r.volume_change, r.expected_volume_change, 0.01 * r.expected_volume_change);
  EXPECT_NEAR(r.u_outer, r.u_outer_lame, 0.03 * r.u_outer_lame);
  EXPECT_NEAR(r.u_inner, r.u_lame, inner * r.u_lame);
}

// The inner wall's vertices converge at first order on this cube-sphere mesh (measured: 16 %, 10 %,
// 5.5 % above Lame at 1, 2, 3 refinements) while the volume and the pressure are already exact.
TEST(Cavity, PressurisedLiquidSettlesAtLamesThickSphereAnswer) { expect_lame(pressurised_octant(1, 2), 0.12); }

// Q2: the wall's faces bulge between their nodes, and the volume they enclose is the law's. On the
// same mesh the inner wall is far closer than P1's (measured: 1.2 % below Lame, P1 10 % above).
TEST(Cavity, QuadraticElementsWithACurvedWallSettleAtLamesAnswer) { expect_lame(pressurised_octant(2, 2), 0.03); }

// The full shell held on the outer faces of a band around its equator, water-filled or empty.
QuasiStaticSolver held_sphere(dealii::Triangulation<3>& tria, const Material& material, bool with_fluid) {
  shell(tria, /*octant=*/false, 1);
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == 1 && std::abs(cell->face(f)->center()[2]) < 0.012)
        cell->face(f)->set_boundary_id(5);
  QuasiStaticSolver solver(tria, material, 1);
  solver.prescribe_displacement(5, {true, true, true}, Tensor<1, 3>());
  if (with_fluid) solver.add_cavity(0, CavityLaw{});  // water
  return solver;
}

struct Pressed {
  double pressure, far_side_uz, near_side_uz, volume_change;  // volume change relative to V0
};

Pressed press_top(bool with_fluid) {
  dealii::Triangulation<3> tria;
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver = held_sphere(tria, material, with_fluid);
  const int probe = solver.add_contact_patch(Point<3>(0, 0, kOuter), 0.015);
  Tensor<1, 3> force;
  force[2] = -0.5;
  solver.set_patch_force(probe, force);
  NewtonSettings settings;
  settings.load_steps = 2;
  const SolveReport report = solver.solve(settings);
  if (!report.converged) throw std::runtime_error("pressed sphere: " + report.failure);
  return {solver.cavity_pressure(), solver.displacement_at(Point<3>(0, 0, -kOuter))[2],
          solver.displacement_at(Point<3>(0, 0, kOuter))[2],
          with_fluid ? solver.cavity_volume() / solver.cavity_reference_volume() - 1 : 0.0};
}

TEST(Cavity, PressingOneSideRaisesThePressureAndBulgesTheFarSide) {
  const Pressed wet = press_top(true), dry = press_top(false);
  std::printf("pressing the top with 0.5 N: water-filled p = %.3f Pa, dV/V0 = %.3e, top u_z %.3e m, bottom u_z %.3e m; "
              "empty: top u_z %.3e m, bottom u_z %.3e m\n",
              wet.pressure, wet.volume_change, wet.near_side_uz, wet.far_side_uz, dry.near_side_uz, dry.far_side_uz);
  EXPECT_GT(wet.pressure, 0.0);
  // Water keeps its volume: dV/V0 = -p/K, about -2.5e-8 here.
  const double bulk = CavityLaw{}.bulk_modulus_pa;
  EXPECT_NEAR(wet.volume_change, -wet.pressure / bulk, 1e-9);
  EXPECT_LT(wet.near_side_uz, 0.0);
  EXPECT_LT(wet.far_side_uz, 0.0) << "the far side bulges outwards (downwards)";
  // The water pushes the far side out well beyond the empty sphere's sag, and holds the top up.
  EXPECT_GT(wet.far_side_uz / dry.far_side_uz, 1.5);
  EXPECT_LT(std::abs(wet.near_side_uz), std::abs(dry.near_side_uz)) << "the incompressible fill stiffens the sphere";
}

// The cavity's own work beyond its assembly (restoring its volume law after a frame's prediction,
// completing each Newton step for its pressure: solves with the factorisation) is timed against it
// in the solve's profile, with the linear iterations it took; elasticity has none of its own.
TEST(Cavity, ItsOwnSolvesAreProfiledAsItsOwn) {
  dealii::Triangulation<3> tria;
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver = held_sphere(tria, material, true);
  const int probe = solver.add_contact_patch(Point<3>(0, 0, kOuter), 0.015);
  Tensor<1, 3> force;
  force[2] = -0.5;
  solver.set_patch_force(probe, force);
  NewtonSettings settings;
  ASSERT_TRUE(solver.solve(settings).converged);
  solver.compliance();  // a haptic frame follows: it starts from the compliance's prediction
  force[2] = -0.6;
  solver.set_patch_force(probe, force);
  const SolveReport frame = solver.solve(settings);
  ASSERT_TRUE(frame.converged);
  int own_iterations = 0;
  for (const SolveReport::TermTime& t : frame.terms) {
    own_iterations += t.linear_iterations;
    if (t.name == std::string("cavity")) {
      EXPECT_GT(t.linear_iterations, 0);
      EXPECT_GT(t.other_s, 0.0);
    } else {
      EXPECT_EQ(t.linear_iterations, 0) << t.name;
    }
  }
  EXPECT_LE(own_iterations, frame.linear_iterations);
}

// Two probes on opposite poles of the water-filled sphere: the compliance W (with the water's
// rank-one stiffness) matches finite differences of the nonlinear solve, and the water couples the
// poles far more than the empty sphere does: pressing the top pushes the bottom out.
TEST(Cavity, ComplianceCouplesOppositeProbesThroughTheWater) {
  const auto coupling = [](bool with_fluid, bool check_fd) {
    dealii::Triangulation<3> tria;
    const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
    QuasiStaticSolver solver = held_sphere(tria, material, with_fluid);
    const int top = solver.add_contact_patch(Point<3>(0, 0, kOuter), 0.015);
    const int bottom = solver.add_contact_patch(Point<3>(0, 0, -kOuter), 0.015);
    Tensor<1, 3> force;
    force[2] = -0.2;
    solver.set_patch_force(top, force);
    NewtonSettings settings;
    settings.relative_tolerance = 1e-12;
    settings.load_steps = 2;
    if (!solver.solve(settings).converged) throw std::runtime_error("pressed sphere did not converge");
    const dealii::FullMatrix<double> w = solver.compliance();
    EXPECT_NEAR(w(2, 5), w(5, 2), 1e-10 * std::abs(w(2, 2)));
    if (check_fd) {  // d(bottom u_z)/d(top F_z) by central differences of the nonlinear solve
      settings.load_steps = 1;
      const double h = 1e-4;
      double u[2];
      for (int side = 0; side < 2; ++side) {
        Tensor<1, 3> f = force;
        f[2] += side == 0 ? h : -h;
        solver.set_patch_force(top, f);
        if (!solver.solve(settings).converged) throw std::runtime_error("finite difference solve failed");
        u[side] = solver.patch_displacement(bottom)[2];
      }
      const double fd = (u[0] - u[1]) / (2 * h);
      std::printf("water: W_top,bottom = %.6e m/N, finite difference %.6e m/N\n", w(2, 5), fd);
      EXPECT_NEAR(w(2, 5), fd, 1e-4 * std::abs(fd));
    }
    return w(2, 5);
  };
  const double wet = coupling(true, true), dry = coupling(false, false);
  std::printf("top-to-bottom coupling: water-filled %.4e m/N, empty %.4e m/N\n", wet, dry);
  EXPECT_GT(wet, 0.0) << "a downward push at the top moves the bottom down (out)";
  EXPECT_GT(wet, 2 * std::abs(dry));
}

// Frames of a press on the water-filled sphere, 6 % more force each: each compliance is the Galerkin
// update that keeps the water's carrier from an earlier frame and takes in the directions the last
// update added. Each W must still be a fresh solver's W at the same load (one that reaches it from
// scratch and solves its columns afresh) to the update's error bound, and both mechanisms must
// have been used.
TEST(Cavity, AFrameComplianceWithKeptDirectionsMatchesAFreshSolve) {
  dealii::Triangulation<3> tria;
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver framed = held_sphere(tria, material, true);
  const int probe = framed.add_contact_patch(Point<3>(0, 0, kOuter), 0.015);
  NewtonSettings settings;
  settings.relative_tolerance = 1e-10;
  settings.load_steps = 2;
  Tensor<1, 3> force;
  force[2] = -0.2;
  framed.set_patch_force(probe, force);
  ASSERT_TRUE(framed.solve(settings).converged);
  framed.compliance();
  settings.load_steps = 1;
  int kept_carriers = 0, recycled = 0;
  for (int frame = 1; frame <= 6; ++frame) {
    force[2] *= 1.06;
    framed.set_patch_force(probe, force);
    ASSERT_TRUE(framed.solve(settings).converged) << "frame " << frame;
    const dealii::FullMatrix<double> w = framed.compliance();
    const ComplianceTimes& times = framed.last_compliance_times();
    kept_carriers += times.carrier_kept;
    recycled += times.recycled_directions > 0;

    dealii::Triangulation<3> fresh_tria;
    QuasiStaticSolver fresh = held_sphere(fresh_tria, material, true);
    fresh.add_contact_patch(Point<3>(0, 0, kOuter), 0.015);
    fresh.set_patch_force(probe, force);
    NewtonSettings from_scratch = settings;
    from_scratch.load_steps = 3;
    ASSERT_TRUE(fresh.solve(from_scratch).converged) << "frame " << frame;
    const dealii::FullMatrix<double> w_fresh = fresh.compliance();
    double worst = 0, largest = 0;
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j) {
        worst = std::max(worst, std::abs(w(i, j) - w_fresh(i, j)));
        largest = std::max(largest, std::abs(w_fresh(i, j)));
      }
    std::printf("frame %d: Galerkin residual %.2e, carrier kept %d, %d directions recycled, solved again %d; "
                "|W - W_fresh| / |W| = %.2e\n",
                frame, times.galerkin_residual, times.carrier_kept, times.recycled_directions, times.refined,
                worst / largest);
    EXPECT_LT(worst, 1e-5 * largest) << "frame " << frame;
    EXPECT_FALSE(times.refined) << "frame " << frame << ": the update did not get there and solved its columns";
  }
  EXPECT_GT(kept_carriers, 0) << "no frame kept the water's carrier";
  EXPECT_GT(recycled, 0) << "no frame took in the last update's directions";
}

TEST(Cavity, RefusesASurfaceThatEnclosesNothing) {
  dealii::Triangulation<3> tria;
  shell(tria, false, 0);
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver(tria, material, 1);
  EXPECT_THROW(solver.add_cavity(1, CavityLaw{}), std::invalid_argument);  // the outer surface
  EXPECT_THROW(solver.add_cavity(7, CavityLaw{}), std::invalid_argument);  // no such faces
}

}  // namespace
}  // namespace fetouch::fem
