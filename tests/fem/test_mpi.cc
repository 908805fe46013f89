// MPI: the same solves on one rank (MPI_COMM_SELF, on each process) and on all ranks together
// (MPI_COMM_WORLD, cells split by METIS, rows by rank, MUMPS or algebraic multigrid in parallel)
// must agree to the solver's tolerance: displacements, patch displacements, reactions and the
// condensed compliance, for P1, P2 and Q1, and through a haptic frame (warm start, Galerkin W).
// Run by ctest under `mpirun -np 2` (label mpi).
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

int world_size() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

void block(dealii::Triangulation<3>& tria, bool simplex) {
  const Point<3> size(0.1, 0.08, 0.05);
  if (simplex)
    dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, {6, 5, 3}, Point<3>(), size);
  else
    dealii::GridGenerator::subdivided_hyper_rectangle(tria, {6, 5, 3}, Point<3>(), size);
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary()) cell->face(f)->set_boundary_id(std::abs(cell->face(f)->center()[2]) < 1e-12 ? 4 : 1);
}

struct Outcome {
  Tensor<1, 3> a, b, reaction, point;
  dealii::FullMatrix<double> w;
  int newton = 0;
};

Outcome press(const dealii::Triangulation<3>& tria, int degree, MPI_Comm comm, bool amg) {
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver(tria, material, degree, comm);
  solver.use_algebraic_multigrid(amg);
  solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  const int a = solver.add_contact_patch(Point<3>(0.035, 0.04, 0.05), 0.012);
  const int b = solver.add_contact_patch(Point<3>(0.065, 0.04, 0.05), 0.012);
  Tensor<1, 3> force;
  force[2] = -0.4;
  force[0] = 0.05;
  solver.set_patch_force(a, force);
  solver.set_patch_force(b, -0.5 * force);
  NewtonSettings settings;
  settings.relative_tolerance = 1e-11;
  settings.load_steps = 2;
  Outcome out;
  const SolveReport report = solver.solve(settings);
  EXPECT_TRUE(report.converged) << report.failure;
  solver.compliance();
  // A haptic frame: 2 % more force, warm start, Galerkin-updated compliance.
  solver.set_patch_force(a, 1.02 * force);
  settings.load_steps = 1;
  const SolveReport frame = solver.solve(settings);
  EXPECT_TRUE(frame.converged) << frame.failure;
  out.newton = report.total_iterations + frame.total_iterations;
  out.w = solver.compliance();
  out.a = solver.patch_displacement(a);
  out.b = solver.patch_displacement(b);
  out.reaction = solver.boundary_force(4);
  out.point = solver.displacement_at(Point<3>(0.05, 0.02, 0.03));
  return out;
}

void expect_same(const Outcome& serial, const Outcome& parallel, double tolerance, const char* what) {
  const double scale = serial.a.norm();
  EXPECT_LT((serial.a - parallel.a).norm(), tolerance * scale) << what;
  EXPECT_LT((serial.b - parallel.b).norm(), tolerance * scale) << what;
  EXPECT_LT((serial.point - parallel.point).norm(), tolerance * scale) << what;
  EXPECT_LT((serial.reaction - parallel.reaction).norm(), tolerance * serial.reaction.norm()) << what;
  double worst = 0, largest = 0;
  for (unsigned int i = 0; i < serial.w.m(); ++i)
    for (unsigned int j = 0; j < serial.w.n(); ++j) {
      worst = std::max(worst, std::abs(serial.w(i, j) - parallel.w(i, j)));
      largest = std::max(largest, std::abs(serial.w(i, j)));
    }
  EXPECT_LT(worst, tolerance * largest) << what;
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0)
    std::printf("%s: |u_a| %.6e m serial, difference %.2e; |W| %.4e m/N, difference %.2e; Newton %d vs %d\n", what,
                scale, (serial.a - parallel.a).norm(), largest, worst, serial.newton, parallel.newton);
}

TEST(Mpi, TwoRanksGiveTheSerialAnswer) {
  ASSERT_GE(world_size(), 2) << "run under mpirun -np 2";
  for (const auto& [simplex, degree, name] : {std::tuple{true, 1, "P1"}, std::tuple{true, 2, "P2"}, std::tuple{false, 1, "Q1"}}) {
    dealii::Triangulation<3> tria;
    block(tria, simplex);
    const Outcome serial = press(tria, degree, MPI_COMM_SELF, false);
    const Outcome parallel = press(tria, degree, MPI_COMM_WORLD, false);
    expect_same(serial, parallel, 1e-8, (std::string(name) + ", direct").c_str());
  }
}

TEST(Mpi, AlgebraicMultigridOnTwoRanksGivesTheSerialDirectAnswer) {
  ASSERT_GE(world_size(), 2) << "run under mpirun -np 2";
  dealii::Triangulation<3> tria;
  block(tria, true);
  const Outcome serial = press(tria, 1, MPI_COMM_SELF, false);
  const Outcome amg_serial = press(tria, 1, MPI_COMM_SELF, true);
  const Outcome amg_parallel = press(tria, 1, MPI_COMM_WORLD, true);
  expect_same(serial, amg_serial, 1e-6, "P1, AMG on one rank");
  expect_same(serial, amg_parallel, 1e-6, "P1, AMG on two ranks");
}

}  // namespace
}  // namespace fetouch::fem
