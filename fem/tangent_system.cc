#include "fem/tangent_system.h"

#include "fem/background_factoriser.h"
#include "fem/petsc_check.h"
#include "fem/stopwatch.h"
#include "fem/tangent_system_petsc.h"

#include <dlfcn.h>
#include <pthread.h>
#include <sched.h>
#include <petscksp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>

namespace fetouch::fem {

void limit_library_threads();

// One thread inside the libraries: CHOLMOD's OpenMP and OpenBLAS's threads would compete with the
// solver's own assembly thread and the haptic thread for the 2 cores. Measured: a frame at 12,240
// DOFs 84 -> 73 ms, and a solve while another process is busy 18 s -> 1.3 s (OpenMP barriers that
// sleep). Found at run time: the functions exist only where the libraries were built with threads.
// OpenMP's setting is per thread: called by every thread that builds a system (and solves with it).
void limit_library_threads() {
  thread_local const bool done = [] {
    using SetThreads = void (*)(int);
    if (auto omp = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_num_threads"))) omp(1);
    // CHOLMOD's supernodal factorisation asks for 4 threads by a num_threads clause (a constant of
    // its build), which omp_set_num_threads does not override: no active parallel level at all does.
    if (auto levels = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"))) levels(0);
    if (auto blas = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) blas(1);
    return true;
  }();
  (void)done;
}


TangentSystem::TangentSystem(MPI_Comm comm) : comm_(comm), petsc_(std::make_unique<Petsc>()) {
  limit_library_threads();
  MPI_Comm_size(comm_, &ranks_);
}


TangentSystem::~TangentSystem() = default;



std::size_t TangentSystem::rows() const { return row_start_.empty() ? 0 : row_start_.size() - 1; }

void TangentSystem::set_pattern(std::vector<int> row_start, std::vector<int> columns, Method method, int owned_begin,
                                int owned_end, const std::vector<std::vector<double>>& near_null_space, int node_block) {
  reset_cholmod();
  petsc_->destroy();
  row_start_ = std::move(row_start);
  columns_ = std::move(columns);
  values_.assign(columns_.size(), 0.0);
  method_ = method;
  owned_begin_ = owned_begin, owned_end_ = owned_end;
  baseline_iterations_ = -1;
  const int n = static_cast<int>(rows());
  diagonal_.resize(n);
  for (int i = 0; i < n; ++i) diagonal_[i] = position(i, i);
  Petsc& p = *petsc_;
  const int local = owned_end - owned_begin;
  if (ranks_ == 1) {
    // PETSc works on these arrays in place: assembly writes values_, PETSc reads them.
    petsc_check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, row_start_.data(), columns_.data(), values_.data(), &p.mat),
          "creating the tangent matrix");
    petsc_check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &p.b), "creating a vector");
    petsc_check(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, n, nullptr, &p.x), "creating a vector");
  } else {
    // The owned rows, copied in by finish().
    local_row_start_.assign(local + 1, 0);
    for (int i = 0; i <= local; ++i) local_row_start_[i] = row_start_[owned_begin + i] - row_start_[owned_begin];
    petsc_check(MatCreateMPIAIJWithArrays(comm_, local, local, n, n, local_row_start_.data(),
                                    columns_.data() + row_start_[owned_begin], values_.data() + row_start_[owned_begin],
                                    &p.mat),
          "creating the distributed tangent matrix");
    petsc_check(VecCreateMPIWithArray(comm_, 1, local, n, nullptr, &p.b), "creating a vector");
    petsc_check(VecCreateMPIWithArray(comm_, 1, local, n, nullptr, &p.x), "creating a vector");
  }
  direct_cholmod_ = ranks_ == 1 && method == Method::factorisation;
  factorisation_flops_ = 0;
  if (direct_cholmod_) set_up_cholmod();
  else if (method == Method::factorisation && rows() <= background_analysed_rows)
    // Several ranks factorise by MUMPS; CHOLMOD's analysis of the same pattern gives the schedule of
    // background factorisations that one rank keeps (background_due_frames).
    factorisation_flops_ = CholeskyFactor(n, row_start_.data(), columns_.data()).flops();
  near_null_vectors_ = static_cast<int>(near_null_space.size());
  node_block_ = node_block;
  near_null_space_.clear();
  for (const auto& v : near_null_space) near_null_space_.insert(near_null_space_.end(), v.begin() + owned_begin, v.begin() + owned_end);
  if (method_ == Method::amg) {
    create_solver(nullptr);
  } else {
    // CHOLMOD's own messages (a matrix that is not positive definite) would reach the terminal.
    PetscBool set = PETSC_FALSE;
    petsc_check(PetscOptionsHasName(nullptr, nullptr, "-mat_cholmod_print", &set), "reading options");
    if (!set) petsc_check(PetscOptionsSetValue(nullptr, "-mat_cholmod_print", "0"), "quietening CHOLMOD");
    create_solver(ranks_ == 1 ? MATSOLVERCHOLMOD : MATSOLVERMUMPS);
  }
}

// CHOLMOD (supernodal LL') by default on one rank: in this use, where factorisations are rare and
// applications many, its triangular solves take half MUMPS's time (bench/bench_fem_frame.cc). It
// needs K positive definite; a tangent that is not (past a limit point) falls back to MUMPS's LDL'.
// In parallel MUMPS throughout; AMG has no factorisation.
void TangentSystem::create_solver(const char* type) {
  Petsc& p = *petsc_;
  if (p.ksp) KSPDestroy(&p.ksp);
  p.factored = false;
  petsc_check(KSPCreate(comm_, &p.ksp), "creating the solver");
  petsc_check(KSPSetType(p.ksp, KSPCG), "choosing CG");
  petsc_check(KSPSetNormType(p.ksp, KSP_NORM_UNPRECONDITIONED), "choosing the residual norm");
  petsc_check(KSPGetPC(p.ksp, &p.pc), "getting the preconditioner");
  char requested[64] = "";
  PetscBool given = PETSC_FALSE;
  petsc_check(PetscOptionsGetString(nullptr, nullptr, "-pc_type", requested, sizeof requested, &given), "reading options");
  gamg_ = method_ == Method::amg && given && std::string(requested) == PCGAMG;
  if (method_ == Method::amg && !gamg_) {
    // Our aggregation of nodes (fem/aggregation_multigrid.h): its levels are built at each set-up
    // (factor()). PETSc's GAMG, below, on request: on a block cut into tetrahedra it made 3 nodes an
    // aggregate and failed its set-up at 334,620 DOFs (docs/benchmarks.md).
    petsc_check(PCSetType(p.pc, PCMG), "choosing algebraic multigrid");
    aggregation_levels_.clear();
    solver_type_ = "aggregation";
  } else if (method_ == Method::amg) {
    petsc_check(PCSetType(p.pc, PCGAMG), "choosing algebraic multigrid");
    // Plain (unsmoothed) aggregation: sparser coarse operators, so a set-up and a V-cycle cost about
    // half as much, for 1.7x the CG iterations. Measured on bench_fem's block at 10,080 DOFs: a
    // frame 8.96 -> 6.33 ms mean, 120 -> 50 ms slowest. PETSC_OPTIONS (-pc_gamg_agg_nsmooths) overrides.
    petsc_check(PCGAMGSetNSmooths(p.pc, 0), "choosing plain aggregation");
    // Aggregates of nodes, not of single dofs (PETSc takes a node's dofs as one vertex of its graph
    // when the matrix has their block size), matched along the heaviest couplings (HEM). PETSc's
    // default (MIS on the graph of single dofs) grouped about five dofs, and each group's 6
    // rigid-body modes made the first coarse level 43 % of the fine one (docs/benchmarks.md).
    petsc_check(MatSetBlockSize(p.mat, node_block_), "telling the nodes");
    PetscBool chosen = PETSC_FALSE;
    petsc_check(PetscOptionsHasName(nullptr, nullptr, "-mat_coarsen_type", &chosen), "reading options");
    if (!chosen) petsc_check(PetscOptionsSetValue(nullptr, "-mat_coarsen_type", "hem"), "choosing the aggregation");
    if (near_null_vectors_ > 0) {
      // The rigid-body modes (orthonormal, as PETSc requires) as GAMG's near-null space.
      const int local = owned_end_ - owned_begin_;
      std::vector<Vec> vectors(near_null_vectors_);
      for (int k = 0; k < near_null_vectors_; ++k) {
        petsc_check(VecCreateMPI(comm_, local, PETSC_DETERMINE, &vectors[k]), "creating a null-space vector");
        double* a = nullptr;
        petsc_check(VecGetArray(vectors[k], &a), "filling a null-space vector");
        std::copy_n(near_null_space_.begin() + std::size_t(k) * local, local, a);
        petsc_check(VecRestoreArray(vectors[k], &a), "filling a null-space vector");
      }
      MatNullSpace space;
      petsc_check(MatNullSpaceCreate(comm_, PETSC_FALSE, near_null_vectors_, vectors.data(), &space), "the near-null space");
      petsc_check(MatSetNearNullSpace(p.mat, space), "setting the near-null space");
      MatNullSpaceDestroy(&space);
      for (Vec& v : vectors) VecDestroy(&v);
    }
    solver_type_ = "gamg";
  } else {
    petsc_check(PCSetType(p.pc, PCCHOLESKY), "choosing Cholesky");
    petsc_check(PCFactorSetMatSolverType(p.pc, type), "choosing the factorisation");
    solver_type_ = type;
    // MUMPS with its null-pivot detection (ICNTL(24) = 1; the threshold, CNTL(3), left at MUMPS's
    // default, which scales with machine precision and K's norm): a tangent that is singular, not only
    // indefinite, is factorised with its null pivots fixed, so that Newton goes on where K has a
    // zero mode. Without it such a K failed every cut of its step, the state being the same: on a
    // fresh mesh of the default scene (CI, 2026-11-30) the teleported probe's frame, at a state
    // where a slide of the patch had converged, failed 9 times with "the tangent stiffness is
    // singular"; with it the frame converged at once. PETSC_OPTIONS overrides.
    if (std::string(type) == MATSOLVERMUMPS) {
      PetscBool chosen = PETSC_FALSE;
      petsc_check(PetscOptionsHasName(nullptr, nullptr, "-mat_mumps_icntl_24", &chosen), "reading options");
      if (!chosen) petsc_check(PetscOptionsSetValue(nullptr, "-mat_mumps_icntl_24", "1"), "choosing null-pivot detection");
    }
  }
  petsc_check(KSPSetOperators(p.ksp, p.mat, p.mat), "setting the operator");
  petsc_check(KSPSetFromOptions(p.ksp), "reading PETSC_OPTIONS");
}

int TangentSystem::position(int row, int column) const {
  const int* begin = columns_.data() + row_start_[row];
  const int* end = columns_.data() + row_start_[row + 1];
  const int* at = std::lower_bound(begin, end, column);
  if (at == end || *at != column)
    throw std::logic_error("tangent: entry (" + std::to_string(row) + ", " + std::to_string(column) +
                           ") is outside the sparsity pattern");
  return static_cast<int>(at - columns_.data());
}

void TangentSystem::zero() { std::fill(values_.begin(), values_.end(), 0.0); }

void TangentSystem::finish(const std::vector<bool>& constrained) {
  const int n = static_cast<int>(rows());
  double sum = 0;
  int free = 0;
  for (int i = 0; i < n; ++i)
    if (!constrained[i]) sum += std::abs(values_[diagonal_[i]]), ++free;
  const double scale = free > 0 && sum > 0 ? sum / free : 1.0;
  diagonal_scale_ = scale;
  for (int i = 0; i < n; ++i)
    if (constrained[i]) values_[diagonal_[i]] = scale;
  if (!direct_cholmod_) push_values();
}

void TangentSystem::push_values() {
  if (ranks_ == 1) {
    // Tells PETSc the values changed (they were written in place).
    petsc_check(MatAssemblyBegin(petsc_->mat, MAT_FINAL_ASSEMBLY), "assembling the tangent");
    petsc_check(MatAssemblyEnd(petsc_->mat, MAT_FINAL_ASSEMBLY), "assembling the tangent");
  } else {
    const int local = owned_end_ - owned_begin_, size = static_cast<int>(rows());
    petsc_check(MatUpdateMPIAIJWithArrays(petsc_->mat, local, local, size, size, local_row_start_.data(),
                                    columns_.data() + row_start_[owned_begin_], values_.data() + row_start_[owned_begin_]),
          "updating the distributed tangent");
  }
}

void TangentSystem::factor(SolveStats& stats) {
  limit_library_threads();
  Petsc& p = *petsc_;
  const auto start = std::chrono::steady_clock::now();
  petsc_check(PCSetReusePreconditioner(p.pc, PETSC_FALSE), "refactorising");
  if (method_ == Method::amg && !gamg_) build_multigrid();  // tangent_system_multigrid.cc
  // CHOLMOD reports a K that is not positive definite as an error: caught quietly, then LDL'.
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  PetscErrorCode code = KSPSetUp(p.ksp);  // the first time
  if (code == 0) code = PCSetUp(p.pc);    // later: K's values changed
  PetscPopErrorHandler();
  PCFailedReason failed = PC_NOERROR;
  if (code == 0) petsc_check(PCGetFailedReason(p.pc, &failed), "checking the factorisation");
  if ((code != 0 || failed != PC_NOERROR) && method_ == Method::factorisation &&
      std::string(solver_type_) != MATSOLVERMUMPS) {
    create_solver(MATSOLVERMUMPS);
    petsc_check(KSPSetUp(p.ksp), "factorising the tangent");
    petsc_check(PCGetFailedReason(p.pc, &failed), "checking the factorisation");
  } else {
    petsc_check(code, "factorising the tangent");
  }
  if (failed != PC_NOERROR) {
    // The preconditioner now holds a failed factorisation, which PETSc would keep (and apply) while
    // the matrix is unchanged: a new solver, so that the next solve factorises afresh (a cut step's
    // smaller load, say).
    create_solver(method_ == Method::amg ? nullptr : solver_type_);
    throw std::runtime_error("the tangent stiffness is singular (factorisation failed)");
  }
  // Later solves keep this factorisation as the preconditioner while K changes.
  petsc_check(PCSetReusePreconditioner(p.pc, PETSC_TRUE), "keeping the factorisation");
  p.factored = true;
  refactor_ = false;
  baseline_iterations_ = -1;
  ++factorisations_;
  stats.refactored = true;
  stats.factor_s += seconds_since(start);
}

void TangentSystem::gather(double* x) const {
  if (ranks_ == 1) return;
  std::vector<int> counts(ranks_), displacements(ranks_);
  const int local = owned_end_ - owned_begin_;
  MPI_Allgather(&local, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_);
  MPI_Allgather(&owned_begin_, 1, MPI_INT, displacements.data(), 1, MPI_INT, comm_);
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, x, counts.data(), displacements.data(), MPI_DOUBLE, comm_);
}

// CHOLMOD's factor, or its single-precision copy where one is kept and double is not asked for.
void TangentSystem::apply_cholmod(const double* b, double* x, int columns) {
  if (in_double_ || !factor_->has_single()) factor_->solve(b, x, columns);
  else factor_->solve_single(b, x, columns);
}

bool TangentSystem::keeps_single_precision() const { return direct_cholmod_ && factor_ && factor_->has_single(); }

bool TangentSystem::factored() const { return direct_cholmod_ ? factor_ && factor_->valid() : petsc_->factored; }

// P^-1 b for one column, P the current factorisation (CHOLMOD's, or PETSc's gathered onto every
// rank), without the rank-one part and untimed.
void TangentSystem::apply_factor(const double* b, double* x) {
  if (direct_cholmod_) return apply_cholmod(b, x, 1);
  Petsc& p = *petsc_;
  petsc_check(VecPlaceArray(p.b, b + owned_begin_), "wrapping a right-hand side");
  petsc_check(VecPlaceArray(p.x, x + owned_begin_), "wrapping a solution");
  const PetscErrorCode code = PCApply(p.pc, p.b, p.x);
  VecResetArray(p.b), VecResetArray(p.x);
  petsc_check(code, "applying the factorisation");
  gather(x);
}

void TangentSystem::set_rank_one(double c, const double* g) {
  rank_one_c_ = g ? c : 0;
  rank_one_g_ = g;
  pg_current_ = false;
}

TangentSystem::SolveStats TangentSystem::apply_factorisation(const double* b, double* x, int columns) {
  SolveStats stats;
  apply_raw(b, x, columns, stats);
  apply_rank_one(x, columns, stats);
  return stats;
}

TangentSystem::SolveStats TangentSystem::apply_factorisation_to_rank_one_g(double* w) {
  SolveStats stats;
  const std::vector<double>& pg = factorised_g(stats);
  const std::size_t n = rows();
  const double scale = 1 / (1 + rank_one_c_ * std::inner_product(rank_one_g_, rank_one_g_ + n, pg.begin(), 0.0));
  for (std::size_t i = 0; i < n; ++i) w[i] = scale * pg[i];
  return stats;
}

const std::vector<double>& TangentSystem::factorised_g(SolveStats& stats) {
  // In the precision of the applications it goes with: one in double needs P^-1 g in double
  // (the rank-one correction would otherwise carry the single copy's rounding into an exact solve).
  if (!pg_current_ || pg_factorisations_ != factorisations_ || (in_double_ && !pg_double_)) {
    pg_.assign(rows(), 0.0);
    apply_raw(rank_one_g_, pg_.data(), 1, stats);
    pg_double_ = in_double_ || !keeps_single_precision();
    pg_current_ = true;
    pg_factorisations_ = factorisations_;
  }
  return pg_;
}

// (P + c g g')^-1 b = P^-1 b - c (g.P^-1 b) / (1 + c g.P^-1 g) P^-1 g. Without it a correction
// would carry a component along g that the rank-one term (a liquid's c ~ 10^12) weighs so heavily
// that a Galerkin projection on such corrections loses every digit.
void TangentSystem::apply_rank_one(double* x, int columns, SolveStats& stats) {
  if (rank_one_c_ == 0) return;
  const std::size_t n = rows();
  const std::vector<double>& pg = factorised_g(stats);
  const double* g = rank_one_g_;
  const double denominator = 1 + rank_one_c_ * std::inner_product(g, g + n, pg.begin(), 0.0);
  for (int k = 0; k < columns; ++k) {
    double* column = x + std::size_t(k) * n;
    const double scale = -rank_one_c_ * std::inner_product(g, g + n, column, 0.0) / denominator;
    for (std::size_t i = 0; i < n; ++i) column[i] += scale * pg[i];
  }
}

void TangentSystem::apply_raw(const double* b, double* x, int columns, SolveStats& stats) {
  // A factorisation that is due first (PETSc's LDL' where CHOLMOD finds K not positive definite).
  if (!factored() || refactor_) factorise(stats);
  const auto start = std::chrono::steady_clock::now();
  const int n = static_cast<int>(rows());
  if (direct_cholmod_) {
    apply_cholmod(b, x, columns);
  } else if (ranks_ == 1 && method_ == Method::factorisation) {
    Petsc& p = *petsc_;
    Mat rhs = nullptr, solution = nullptr;
    petsc_check(MatCreateSeqDense(PETSC_COMM_SELF, n, columns, const_cast<double*>(b), &rhs), "wrapping right-hand sides");
    petsc_check(MatCreateSeqDense(PETSC_COMM_SELF, n, columns, x, &solution), "wrapping solutions");
    const PetscErrorCode code = PCMatApply(p.pc, rhs, solution);
    MatDestroy(&rhs);
    MatDestroy(&solution);
    petsc_check(code, "applying the factorisation to a block");
  } else {  // one column at a time
    for (int k = 0; k < columns; ++k) apply_factor(b + std::size_t(k) * n, x + std::size_t(k) * n);
  }
  stats.solve_s += seconds_since(start);
}


}  // namespace fetouch::fem
