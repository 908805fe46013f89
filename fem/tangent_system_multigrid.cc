// TangentSystem with algebraic multigrid: our aggregation's hierarchy built at each set-up, its
// levels as reported, and CG (GMRES where K is not positive definite) preconditioned by a V-cycle.
// tangent_system.h says why.
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "fem/aggregation_multigrid.h"
#include "fem/petsc_check.h"
#include "fem/stopwatch.h"
#include "fem/tangent_system.h"
#include "fem/tangent_system_petsc.h"

namespace fetouch::fem {

void TangentSystem::build_multigrid() {
  Petsc& p = *petsc_;
  // A fresh PCMG each set-up: the levels' sizes change with K (held nodes, contact), and PETSc
  // will not give a set-up KSP an operator of another size.
  create_solver(nullptr);
  try {
    AggregationSettings settings;
    settings.node_block = node_block_;
    // PETSC_OPTIONS=-fetouch_aggregation_smoothings 1: smoothed aggregation (docs/benchmarks.md).
    PetscInt smoothings = settings.smoothings;
    petsc_check(PetscOptionsGetInt(nullptr, nullptr, "-fetouch_aggregation_smoothings", &smoothings, nullptr), "reading options");
    settings.smoothings = static_cast<int>(smoothings);
    aggregation_levels_ =
        build_aggregation_multigrid(p.pc, p.mat, near_null_space_.data(), near_null_vectors_, settings);
  } catch (const std::runtime_error&) {
    create_solver(nullptr);  // no half-built hierarchy is kept
    throw;
  }
}

std::vector<TangentSystem::Level> TangentSystem::multigrid_levels() const {
  std::vector<Level> levels;
  const Petsc& p = *petsc_;
  PetscInt count = 0;
  if (method_ != Method::amg || !p.pc) return levels;
  if (!gamg_) return aggregation_levels_;
  if (PCMGGetLevels(p.pc, &count) != 0) return levels;
  for (PetscInt level = count - 1; level >= 0; --level) {  // PCMG numbers the coarsest 0
    KSP smoother = nullptr;
    Mat a = nullptr;
    MatInfo info;
    PetscInt rows = 0;
    if (PCMGGetSmoother(p.pc, level, &smoother) != 0 || KSPGetOperators(smoother, &a, nullptr) != 0 ||
        MatGetSize(a, &rows, nullptr) != 0 || MatGetInfo(a, MAT_GLOBAL_SUM, &info) != 0)
      return {};
    levels.push_back({static_cast<std::size_t>(rows), static_cast<std::size_t>(info.nz_used)});
  }
  return levels;
}

double TangentSystem::operator_complexity(const std::vector<Level>& levels) {
  if (levels.empty() || levels[0].nonzeros == 0) return 0;
  double nonzeros = 0;
  for (const Level& level : levels) nonzeros += static_cast<double>(level.nonzeros);
  return nonzeros / static_cast<double>(levels[0].nonzeros);
}

TangentSystem::SolveStats TangentSystem::solve(const double* b, double* x, double tolerance, bool zero_guess) {
  if (direct_cholmod_ || method_ == Method::factorisation) return solve_factorised(b, x, tolerance, zero_guess);
  // Multigrid: PETSc's CG, preconditioned by our aggregation's V-cycle (or GAMG's).
  Petsc& p = *petsc_;
  SolveStats stats;
  const int n = static_cast<int>(rows());
  if (zero_guess) std::fill(x, x + n, 0.0);
  // Each rank hands PETSc its owned block of the whole vectors.
  petsc_check(VecPlaceArray(p.b, b + owned_begin_), "wrapping the right-hand side");
  petsc_check(VecPlaceArray(p.x, x + owned_begin_), "wrapping the solution");
  struct Unplace {
    Petsc& p;
    ~Unplace() { VecResetArray(p.b), VecResetArray(p.x); }
  } unplace{p};
  const auto cg = [&](int limit) {
    const auto start = std::chrono::steady_clock::now();
    petsc_check(KSPSetInitialGuessNonzero(p.ksp, PETSC_TRUE), "setting the initial guess");
    petsc_check(KSPSetTolerances(p.ksp, tolerance, 0.0, 1e30, limit), "setting tolerances");
    petsc_check(KSPSolve(p.ksp, p.b, p.x), "conjugate gradients");
    KSPConvergedReason reason;
    PetscInt iterations;
    petsc_check(KSPGetConvergedReason(p.ksp, &reason), "checking convergence");
    petsc_check(KSPGetIterationNumber(p.ksp, &iterations), "counting iterations");
    stats.iterations += static_cast<int>(iterations);
    stats.solve_s += seconds_since(start);
    if (reason > 0) {
      if (baseline_iterations_ < 0) baseline_iterations_ = static_cast<int>(iterations);
      // Multigrid drifts from its own first count (a factorisation from one iteration: solve_factorised).
      if (iterations > std::max(refactor_after_iterations, 3 * baseline_iterations_ / 2)) refactor_ = true;
    }
    return reason > 0;
  };
  // No hierarchy yet, one due, or CG on the old one failed (it drifted too far from K, or K lost
  // definiteness): set up again, then solve by CG on the fresh multigrid.
  if (!p.factored || refactor_ || !cg(1000)) {
    factor(stats);
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    bool solved = cg(1000);
    if (!solved) petsc_check(KSPGetConvergedReason(p.ksp, &reason), "checking convergence");
    if (!solved && reason == KSP_DIVERGED_INDEFINITE_MAT) {
      // K is not positive definite here (Newton passing a state where some elements are squeezed
      // hard: the 334,620-DOF press met one in its 13th solve, CG stopping after 2 iterations on a
      // fresh hierarchy). GMRES on the same multigrid does not need K definite; the next solve is
      // CG again. Right-preconditioned, so that its residual is K's own, as CG's.
      petsc_check(VecZeroEntries(p.x), "restarting from zero");
      petsc_check(KSPSetType(p.ksp, KSPGMRES), "choosing GMRES");
      petsc_check(KSPGMRESSetRestart(p.ksp, 200), "choosing GMRES");
      petsc_check(KSPSetPCSide(p.ksp, PC_RIGHT), "choosing GMRES");
      petsc_check(KSPSetNormType(p.ksp, KSP_NORM_UNPRECONDITIONED), "choosing the residual norm");
      solved = cg(1000);
      petsc_check(KSPSetType(p.ksp, KSPCG), "choosing CG");
      petsc_check(KSPSetPCSide(p.ksp, PC_LEFT), "choosing CG");
      petsc_check(KSPSetNormType(p.ksp, KSP_NORM_UNPRECONDITIONED), "choosing the residual norm");
      ++indefinite_solves_;
    }
    if (!solved) {
      // Multigrid cannot carry every tangent: nearly incompressible tissue (nu -> 0.5), where the
      // volumetric stiffness dwarfs the shear, left CG at its limit on every load step (the random
      // scenes found it: 32 failed frames of 42). A sparse factorisation (MUMPS) can, at its cost:
      // this system factorises from here on.
      method_ = Method::factorisation;
      create_solver(MATSOLVERMUMPS);
      factor(stats);
      const auto start = std::chrono::steady_clock::now();
      petsc_check(PCApply(p.pc, p.b, p.x), "solving with the factorisation");
      stats.solve_s += seconds_since(start);
    }
  }
  gather(x);
  return stats;
}

}  // namespace fetouch::fem
