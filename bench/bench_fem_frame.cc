// One solver frame of the default kind of scene (ARCHITECTURE.md section 7: under 50 ms, i.e. 20 Hz,
// on 2 cores): a neo-Hookean block fixed at its base, two probes pressing 0.3 N, one of them
// pressing and releasing by 30 % over 5 s (100 frames; up to 1.9 % force change per frame), Newton
// (1e-8 relative residual) continuing from the previous frame's state, then the 2-contact condensed
// compliance. CG preconditioned by a sparse Cholesky factorisation refactored when stale (amg:0), or
// by algebraic multigrid (amg:1). policy:0 stops Newton at 1e-8 relative residual (NewtonSettings'
// defaults); policy:1 at the scene's default accuracy policy (contacts within 10 um, 1 mN out of
// balance, W to 1e-3, at most 4 Newton iterations a frame). Serial, or under mpirun -np 2 (a fixed
// 60 frames per case).
// Assembly: one residual and tangent assembly of the same block, on 1 or 2 threads (nothing else
// running: the frame's background factorisation shares the second core), with the split tangent
// kernel the solver uses (split:1) or the full 81-entry tangent's (split:0, FullTangentOnly).
//   build/release/bench/bench_fem --benchmark_filter=Frame
#include <benchmark/benchmark.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fem/full_tangent_only.h"
#include "fem/material.h"
#include "fem/mpi_session.h"
#include "fem/quasi_static_solver.h"

#include <mpi.h>

namespace {

using namespace fetouch::fem;

// The 10 x 8 x 5 cm block, (n + 2) x (n + 1) x n hexahedra each split into tetrahedra; base id 4.
void block(dealii::Triangulation<3>& tria, unsigned int n) {
  dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, {n + 2, n + 1, n}, dealii::Point<3>(),
                                                                   dealii::Point<3>(0.1, 0.08, 0.05));
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary()) cell->face(f)->set_boundary_id(std::abs(cell->face(f)->center()[2]) < 1e-12 ? 4 : 1);
}

// The block's base fixed and two probes pressing 0.3 N; returns the first probe's patch (the one
// the frames press and release).
int press_with_two_probes(QuasiStaticSolver& solver) {
  solver.prescribe_displacement(4, {true, true, true}, dealii::Tensor<1, 3>());
  const int a = solver.add_contact_patch(dealii::Point<3>(0.035, 0.04, 0.05), 0.01);
  const int b = solver.add_contact_patch(dealii::Point<3>(0.065, 0.04, 0.05), 0.01);
  dealii::Tensor<1, 3> force;
  force[2] = -0.3;
  solver.set_patch_force(a, force);
  solver.set_patch_force(b, force);
  return a;
}

void BM_FemFrame(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const unsigned int n = static_cast<unsigned int>(state.range(1));
  dealii::Triangulation<3> tria;
  block(tria, n);
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver(tria, material, degree);
  solver.use_algebraic_multigrid(state.range(2) != 0);
  NewtonSettings newton;
  if (state.range(3) != 0) {  // the scene's defaults (config/scene.h)
    newton.position_tolerance_m = 1e-5;
    newton.force_tolerance_n = 1e-3;
    newton.frame_iterations = 4;
    solver.set_compliance_accuracy(1e-3);
  }
  const int a = press_with_two_probes(solver);
  dealii::Tensor<1, 3> force;
  solver.solve(newton);
  solver.compliance();
  long frame = 0, iterations = 0, cg = 0, factorisations = 0;
  double assembly = 0, factorisation = 0, solves = 0, compliance_s = 0;
  double worst = 0;
  long slowest = 0;
  std::vector<double> times;
  // FETOUCH_TRACE_FRAMES prints the frames over 30 ms, or over FETOUCH_TRACE_FRAMES_OVER_MS.
  const bool trace = std::getenv("FETOUCH_TRACE_FRAMES") != nullptr;
  const char* over = std::getenv("FETOUCH_TRACE_FRAMES_OVER_MS");
  const double trace_over_s = over ? 1e-3 * std::atof(over) : 0.03;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    // A press and release over 5 s at 20 Hz: the force changes by up to 1.9 % per frame.
    force[2] = -0.3 * (1 + 0.3 * std::sin(2 * M_PI * static_cast<double>(++frame) / 100));
    solver.set_patch_force(a, force);
    const SolveReport report = solver.solve(newton);
    iterations += report.total_iterations;
    const auto compliance_start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(solver.compliance());
    compliance_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - compliance_start).count();
    const ComplianceTimes& c = solver.last_compliance_times();
    cg += report.linear_iterations + c.linear_iterations;
    factorisations += report.factorisations + c.factorisations;
    const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (took > worst) worst = took, slowest = frame;
    if (trace && took > trace_over_s)
      std::fprintf(stderr, "frame %ld: %.1f ms; %s\n", frame, 1e3 * took, describe_frame(report, c).c_str());
    times.push_back(took);
    assembly += report.assembly_s + c.assembly_s;
    factorisation += report.factorisation_s + c.factorisation_s;
    solves += report.solve_s + c.solves_s;
  }
  const double frames = static_cast<double>(std::max(1L, frame));
  state.counters["dofs"] = solver.dofs();
  state.counters["newton_per_frame"] = iterations / frames;
  state.counters["max_frame_ms"] = 1e3 * worst;
  state.counters["slowest_frame"] = static_cast<double>(slowest);  // 1: the first after the static solve
  std::sort(times.begin(), times.end());
  state.counters["p99_frame_ms"] = times.empty() ? 0.0 : 1e3 * times[std::min(times.size() - 1, times.size() * 99 / 100)];
  state.counters["cg_per_frame"] = cg / frames;
  state.counters["factor_per_frame"] = factorisations / frames;
  state.counters["assembly_ms"] = 1e3 * assembly / frames;
  state.counters["factor_ms"] = 1e3 * factorisation / frames;
  state.counters["solves_ms"] = 1e3 * solves / frames;
  state.counters["compliance_ms"] = 1e3 * compliance_s / frames;
}
void BM_FemAssembly(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const unsigned int n = static_cast<unsigned int>(state.range(1));
  dealii::Triangulation<3> tria;
  block(tria, n);
  const NeoHookean neo_hookean(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  const FullTangentOnly full(neo_hookean);
  const Material& material = state.range(3) ? static_cast<const Material&>(neo_hookean) : full;
  QuasiStaticSolver solver(tria, material, degree);
  solver.set_assembly_threads(static_cast<unsigned int>(state.range(2)));
  solver.prescribe_displacement(4, {true, true, true}, dealii::Tensor<1, 3>());
  NewtonSettings once;  // a solve that stops at its first assembly (residual and tangent)
  once.absolute_tolerance = 1e30;
  solver.solve(once);
  for (auto _ : state) state.SetIterationTime(solver.solve(once).assembly_s);
  state.counters["dofs"] = solver.dofs();
}
// The linear solver alone against DOFs (issue 38): the block under the two probes' 0.3 N, solved
// statically, then the first condensed compliance: 6 columns K z = h solved from zero to 1e-9 with
// the converged tangent. Counters: the multigrid set-up or the factorisation that solve made
// (setup_ms), CG iterations per column, time per column and per CG iteration. One iteration a case
// (the set-up is most of a case's time).
void BM_FemLinearSolve(benchmark::State& state) {
  const unsigned int n = static_cast<unsigned int>(state.range(0));
  dealii::Triangulation<3> tria;
  block(tria, n);
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  QuasiStaticSolver solver(tria, material, 1);
  solver.use_algebraic_multigrid(state.range(1) != 0);
  press_with_two_probes(solver);
  NewtonSettings newton;
  const SolveReport report = solver.solve(newton);
  for (auto _ : state) benchmark::DoNotOptimize(solver.compliance());
  const ComplianceTimes& c = solver.last_compliance_times();
  state.counters["dofs"] = solver.dofs();
  state.counters["static_newton"] = report.total_iterations;
  state.counters["static_cg_per_newton"] = report.linear_iterations / std::max(1.0, double(report.total_iterations));
  state.counters["static_setup_ms"] = 1e3 * report.factorisation_s;
  state.counters["setup_ms"] = 1e3 * c.factorisation_s;
  state.counters["cg_per_column"] = c.linear_iterations / 6.0;
  state.counters["ms_per_column"] = 1e3 * c.solves_s / 6;
  state.counters["ms_per_cg"] = c.linear_iterations > 0 ? 1e3 * c.solves_s / c.linear_iterations : 0.0;
  // AMG's hierarchy: levels, the first coarse level's rows against the fine one's, and the operator
  // complexity (all levels' nonzeros over the fine level's).
  const auto levels = solver.multigrid_levels();
  if (!levels.empty()) {
    state.counters["levels"] = static_cast<double>(levels.size());
    state.counters["coarse_ratio"] = levels.size() > 1 ? double(levels[1].rows) / double(levels[0].rows) : 0.0;
    state.counters["op_complexity"] = TangentSystem::operator_complexity(levels);
  }
}
}  // namespace

int main(int argc, char** argv) {
  fetouch::fem::MpiSession mpi(argc, argv);
  // Under mpirun every rank runs the same frames together: a fixed number of them (Google
  // Benchmark would otherwise let each rank pick its own count, and the collective solves hang).
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  auto* frames = benchmark::RegisterBenchmark("BM_FemFrame", BM_FemFrame);
  frames->ArgNames({"degree", "n", "amg", "policy"})->Unit(benchmark::kMillisecond);
  for (const int policy : {1, 0})
    for (const int amg : {0, 1}) {
      for (const int n : {6, 10, 13, 14, 16, 18, 20}) frames->Args({1, n, amg, policy});
      for (const int n : {3, 5, 6, 7, 9}) frames->Args({2, n, amg, policy});
    }
  // Direct against AMG from 10,080 to 191,880 DOFs, across auto's switch (docs/benchmarks.md): one
  // whole press-and-release cycle each.
  auto* large = benchmark::RegisterBenchmark("BM_FemFrameLarge", BM_FemFrame);
  large->ArgNames({"degree", "n", "amg", "policy"})->Unit(benchmark::kMillisecond)->Iterations(100);
  for (const int n : {13, 18, 22, 24, 26, 28, 30, 31, 38})
    for (const int amg : {0, 1}) large->Args({1, n, amg, 1});
  // 17,442 to 421,668 DOFs; the direct path to 191,880 (a factorisation at 421,668 takes minutes).
  auto* linear = benchmark::RegisterBenchmark("BM_FemLinearSolve", BM_FemLinearSolve);
  linear->ArgNames({"n", "amg"})->Unit(benchmark::kMillisecond)->Iterations(1);
  for (const int n : {16, 22, 31, 38, 50})
    for (const int amg : {0, 1})
      if (amg == 1 || n < 50) linear->Args({n, amg});
  auto* assembly = benchmark::RegisterBenchmark("BM_FemAssembly", BM_FemAssembly);
  assembly->ArgNames({"degree", "n", "threads", "split"})->Unit(benchmark::kMillisecond)->UseManualTime();
  for (const int threads : {1, 2}) {
    for (const int split : {1, 0}) {
      for (const int n : {10, 14, 20}) assembly->Args({1, n, threads, split});
      for (const int n : {5, 9}) assembly->Args({2, n, threads, split});
    }
  }
  if (ranks > 1) frames->Iterations(60), large->Iterations(60);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
