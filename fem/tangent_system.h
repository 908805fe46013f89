// The tangent stiffness K in compressed sparse rows, written directly by the assembly loop, and the
// linear solves with it.
//
// A frame of the haptic loop changes the probe forces a little, so the tangent changes a little
// from frame to frame. Factorising it every Newton iteration (the textbook Newton method) costs more
// than a 20 Hz frame allows at 10,000 unknowns on 2 cores, while a factorisation of the tangent of
// an earlier state is an excellent preconditioner for the current one. So solves run conjugate
// gradients on the current K, preconditioned by a sparse Cholesky factorisation (CHOLMOD, or MUMPS's
// LDL' where K is not positive definite; both through PETSc) of
// K at the last refactorisation, and refactor when CG needs more than a few iterations (the state
// has drifted) or fails; a freshly factorised system is solved directly. Newton's quadratic
// convergence is kept: the steps solve the current tangent to a tolerance the caller chooses.
//
// Constrained (fixed) unknowns are rows and columns with only a diagonal entry, of the size of the
// mean free diagonal so that the preconditioner sees a well-scaled matrix.
//
// On one rank the factorisation is CHOLMOD's supernodal LL', called directly (cholesky_factor.h).
// CG with a factorisation is this class's own on every path (CHOLMOD, or PETSc's MUMPS on several
// ranks), so that a solve takes the same iterations on any number of ranks. Within haptic frames
// (begin_frame(true)) a solve never pays a factorisation: when CG needs more than
// refactor_after_iterations, the current K is handed to a worker thread that factorises it while
// frames go on with the old factorisation, and the new one is taken up at the start of the frame
// background_due_frames() later, 1 to `swap_after_frames` as its flops take (waited for there if not
// ready, so lockstep replays stay
// bit-reproducible; undeterministic mode, real time, takes it up there if it is ready and otherwise
// at the first frame after at which it is: background_late()).
// A K that is not positive definite is factorised by PETSc's MUMPS LDL', and the solves go back
// to CHOLMOD at the first K that is again (the worker's, within frames; the next factorisation,
// outside them).
//
// Or, selectable (and chosen by size in the scene), CG preconditioned by algebraic multigrid
// (smoothed aggregation of nodes, each with its neighbourhood, carrying the rigid-body modes as
// the near-null space: fem/aggregation_multigrid.h, run by PETSc's PCMG; PETSc's own GAMG when
// PETSC_OPTIONS says -pc_type gamg), set up again when CG needs half as many iterations again as it
// did after the last set-up.
//
// In parallel the matrix is PETSc's MPIAIJ over a communicator, each rank owning a contiguous block
// of rows, with MUMPS as the factorisation (CHOLMOD is serial). Every rank keeps the whole CSR
// pattern and values (the solver reduces them) and whole right-hand sides and solutions: solves
// gather the solution onto every rank. Needs MPI initialised (fem::MpiSession).
#pragma once

#include <mpi.h>

#include <cstddef>
#include <memory>
#include <vector>

#include "fem/cholesky_factor.h"
#include "fem/multigrid_level.h"

namespace fetouch::fem {

class TangentSystem {
 public:
  enum class Method { factorisation, amg };
  explicit TangentSystem(MPI_Comm comm = MPI_COMM_SELF);
  ~TangentSystem();
  TangentSystem(const TangentSystem&) = delete;
  TangentSystem& operator=(const TangentSystem&) = delete;

  // The sparsity: row_start (rows + 1 entries) and the column indices of each row, sorted; this
  // rank owns rows [owned_begin, owned_end) (all of them on one rank). A new pattern drops the
  // factorisation. For AMG: `near_null_space`, the rigid-body modes (each a whole vector), and
  // `node_block`, the dofs a node (3 where rows 3k..3k+2 are one node's x, y, z).
  void set_pattern(std::vector<int> row_start, std::vector<int> columns, Method method, int owned_begin, int owned_end,
                   const std::vector<std::vector<double>>& near_null_space = {}, int node_block = 1);
  Method method() const { return method_; }
  std::size_t rows() const;
  std::size_t nonzeros() const { return values_.size(); }

  // Assembly: zero(), add(...) for every element entry, then finish(constrained).
  void zero();
  // K(row, column) += value; the entry must be in the pattern.
  void add(int row, int column, double value) { values_[position(row, column)] += value; }
  int position(int row, int column) const;
  double* values() { return values_.data(); }
  // Constrained rows and columns become diagonal (the caller skipped their entries), with the free
  // diagonal's mean magnitude, which diagonal_scale() then gives (N/m: a stiffness per dof).
  void finish(const std::vector<bool>& constrained);
  double diagonal_scale() const { return diagonal_scale_; }

  // y = K x; or y = A x for another value array A of the same pattern.
  void multiply(const double* x, double* y) const { multiply(values_.data(), x, y); }
  void multiply(const double* values, const double* x, double* y) const;
  // y[k] = K x[k] for `columns` vectors at once: K is read once for all of them (the product is
  // bound by memory bandwidth, and K is most of the bytes).
  void multiply_columns(const double* const* x, double* const* y, int columns) const;

  struct SolveStats {
    int iterations = 0;       // CG iterations (0 when solved directly after a refactorisation)
    bool refactored = false;
    bool rank_one = false;    // the solve was with K + c g g' (set_rank_one), not K alone
    double factor_s = 0, solve_s = 0;
  };
  // A dense rank-one part c g g' of the operator (a liquid's volume constraint: c up to 10^13), or
  // none (c = 0). g has rows() entries and must outlive the solves; rank_one_moved() when its values
  // change. With a factorisation, solve() then solves with K + c g g' itself (CG on it,
  // preconditioned by (P + c g g')^-1 by Sherman-Morrison; SolveStats::rank_one set); the multigrid
  // path solves with K alone and leaves the rank-one part to the caller. apply_factorisation() always
  // applies (P + c g g')^-1.
  void set_rank_one(double c, const double* g);
  void rank_one_moved() { pg_current_ = false; }
  // x = K^-1 b to a relative residual |b - K x| <= tolerance |b|; x holds the initial guess (or is
  // zeroed when `zero_guess`). Refactors when there is no factorisation, when asked to, or when CG
  // does not reach the tolerance within max_cg_iterations. Throws std::runtime_error on a PETSc
  // failure (a singular tangent).
  SolveStats solve(const double* b, double* x, double tolerance, bool zero_guess);
  // X = P^-1 B for `columns` right-hand sides at once (column-major, rows() x columns), P the current
  // factorisation (made first if there is none or one is due): one preconditioner application per
  // column, in a single blocked triangular solve. Not a solve with K unless just refactored.
  SolveStats apply_factorisation(const double* b, double* x, int columns);
  // w = (P + c g g')^-1 g for the rank-one part's own g: P^-1 g (kept while g and P stay the same)
  // scaled by 1 / (1 + c g'P^-1 g), so at most one triangular solve.
  SolveStats apply_factorisation_to_rank_one_g(double* w);
  // The next solve factorises the current K first (after load-step cuts, a new pattern, ...).
  void refactor_next() { refactor_ = true; }
  // The start of a solver call: `frame` true for a haptic frame (factorisations in the background),
  // false for other solves (a stale factorisation is replaced at once, as before).
  // Returns the seconds it waited for a background factorisation.
  double begin_frame(bool frame);  // collective under MPI
  void set_deterministic(bool on) { deterministic_ = on; }
  // A background factorisation is due ceil(F / background_flops_per_frame) frames after its request,
  // F the flops of one factorisation of this pattern (CHOLMOD's symbolic analysis, on any number of
  // ranks, so that every rank count keeps one schedule), at least 1 and at most swap_after_frames;
  // swap_after_frames itself for patterns over background_analysed_rows rows or with
  // background_flops_per_frame 0. The default, 4 x 10^8, is 20 ms at the 20 GFlop/s this 2-core
  // VM's one core factorises at: the compute of a frame that asks for a factorisation (one Newton
  // iteration and a compliance update, 15-25 ms on the anatomy), which is all the worker gets where
  // frames follow each other at once (lockstep replays, studies). Real time gives it the whole 50 ms
  // period, so it is ready there either way; lockstep, which waits for it, waited 10-15 ms in every
  // other slow frame with 10^9 (the anatomy at 8 mm: 5 x 10^8 flops, 22 ms; with the 4 mm ball
  // 7.2 x 10^8). A factorisation is taken up one frame later than it could be at best: a few CG
  // iterations of 0.5 ms more on the old one.
  int swap_after_frames = 3;
  double background_flops_per_frame = 4e8;
  std::size_t background_analysed_rows = 60'000;
  int background_due_frames() const;
  // CG on a stale factorisation applies a single-precision copy of it (the same supernodal factor
  // with its entries rounded, solved by the BLAS's single-precision routines): half the bytes of a
  // triangular solve, which streams the factor and is bound by memory bandwidth. A factorisation
  // used as the solution itself (just made) is applied in double. Only for a factor of at least
  // single_precision_min_entries entries: a smaller one stays in the cache, where halving its bytes
  // gains little and its rounding, about the condition number times 6e-8, would count as drift
  // (the fetal phantom's factor: 1.67 M entries as the supernodes lay them out, its presses' factor
  // applications 1.7 times faster and no more CG iterations). Read when the pattern is set.
  bool single_precision_preconditioner = true;
  std::size_t single_precision_min_entries = 1'000'000;
  // CG to a tighter relative residual than this applies the double factor (a frame's steps, solved to
  // the accuracy policy, ask for far less; a static solve's 1e-8 would cost the single copy's CG an
  // iteration more than the double factor's, every time).
  static constexpr double kSinglePrecisionTolerance = 1e-6;
  // A single-precision copy of the current factorisation is kept (and used as above).
  bool keeps_single_precision() const;
  // CG iterations allowed on a stale factorisation while a new one is made in the background.
  int max_background_cg_iterations = 30;
  int background_factorisations() const { return background_factorisations_; }
  // This frame went on with the old factorisation where lockstep takes up the background one (not
  // deterministic, and that one not ready): from here the frames differ from lockstep's within the
  // solves' tolerance, where until now they were the same bit for bit.
  bool background_late() const { return background_late_; }
  int late_background_frames() const { return late_background_frames_; }  // so far
  // Requests made while the worker still made its warm-up factorisation: queued behind it, not waited
  // for (the frame that asked goes on at once; lockstep waits, if at all, where it takes the result up).
  int requests_queued_behind_warm_up() const { return queued_requests_; }
  // A factorisation requested for the background and not yet taken up (on the worker, or done there).
  bool background_under_way() const { return frames_since_request_ >= 0; }
  // The worker is factorising at this moment (not waiting, not done): it then holds a core.
  bool background_factorising() const;
  int max_cg_iterations = 8;
  // When CG took more than this many iterations, the next solve refactors.
  int refactor_after_iterations = 5;
  // Factorisations so far.
  int factorisations() const { return factorisations_; }
  // One rank: the solves are on CHOLMOD's factorisation now (false on MUMPS's, for a K that was not
  // positive definite, until a K that is is factorised); and how often they left it so far.
  bool cholmod() const { return direct_cholmod_; }
  int cholmod_departures() const { return cholmod_departures_; }
  // Multigrid solves that met a K that is not positive definite and were solved by GMRES.
  int indefinite_solves() const { return indefinite_solves_; }
  // AMG's hierarchy as set up last, the fine level first: rows and stored entries (nonzeros) of each
  // level's operator. Empty for the direct path and before the first AMG solve. Collective under MPI.
  // Under our aggregation, also the aggregates of each level's nodes and their mean size (0 on the
  // coarsest and under GAMG).
  using Level = MultigridLevel;
  std::vector<Level> multigrid_levels() const;
  // All levels' nonzeros over the fine level's (0 without levels).
  static double operator_complexity(const std::vector<Level>& levels);

 private:
  void factor(SolveStats& stats);
  // CG preconditioned by the current factorisation, CHOLMOD's or PETSc's (tangent_system_cholmod.cc).
  SolveStats solve_factorised(const double* b, double* x, double tolerance, bool zero_guess);
  bool factored() const;                            // a factorisation to precondition with
  void factorise(SolveStats& stats);               // K now (CHOLMOD, or MUMPS's LDL' where K is not positive definite)
  void apply_factor(const double* b, double* x);  // P^-1 b, one column, untimed
  void apply_cholmod(const double* b, double* x, int columns);  // P^-1 B, in the precision in_double_ says
  bool factor_cholmod(SolveStats& stats);  // false: not positive definite (leave_cholmod: MUMPS's LDL' for it)
  void leave_cholmod();  // MUMPS's LDL' for this K, until a K that is positive definite
  void set_up_cholmod();
  void reset_cholmod();
  void request_background();
  void push_values();  // tells PETSc the values changed
  double take_background(bool wait);
  void create_solver(const char* type);
  void gather(double* x) const;  // the owned block of x from each rank, onto every rank
  const char* solver_type_ = nullptr;
  MPI_Comm comm_;
  int ranks_ = 1;
  Method method_ = Method::factorisation;
  double diagonal_scale_ = 0;
  int owned_begin_ = 0, owned_end_ = 0;
  int baseline_iterations_ = -1;  // of the first CG solve after a set-up
  std::vector<int> local_row_start_;  // the owned rows' offsets, from 0 (parallel)
  std::vector<double> near_null_space_;
  int near_null_vectors_ = 0;
  int node_block_ = 1;
  bool gamg_ = false;                      // PETSc's GAMG instead of our aggregation
  int indefinite_solves_ = 0;              // multigrid solves that needed GMRES (K not positive definite)
  std::vector<Level> aggregation_levels_;  // our aggregation's, as set up last
  std::vector<int> row_start_, columns_, diagonal_;
  std::vector<double> values_;
  bool refactor_ = true;
  int factorisations_ = 0;
  struct Petsc;
  void build_multigrid();  // our aggregation's levels into the PC (factor())
  std::unique_ptr<Petsc> petsc_;
  // One rank, factorisation: CHOLMOD directly, a worker for background factorisations. The solves
  // leave it for MUMPS while K is not positive definite (leave_cholmod), and come back.
  bool direct_cholmod_ = false;
  int cholmod_departures_ = 0;
  double factorisation_flops_ = 0;  // of CHOLMOD's factorisation of this pattern (0: not analysed)
  std::unique_ptr<CholeskyFactor> factor_;
  struct Worker;
  std::unique_ptr<Worker> worker_;
  bool in_frame_ = false, deterministic_ = true;
  // The factorisation is applied in double precision (its single copy otherwise, where kept): as
  // the solution itself, for P^-1 g of the rank-one part, and in CG to tolerances the single
  // copy's rounding would reach. Set within a scope by InDouble.
  bool in_double_ = false;
  struct InDouble {
    bool& flag;
    const bool saved;
    InDouble(bool& f, bool on) : flag(f), saved(f) { flag = flag || on; }
    ~InDouble() { flag = saved; }
  };
  bool primed_ = false;  // the worker has made its first (warm-up) factorisation for this pattern
  int frames_since_request_ = -1;  // -1: no background factorisation under way
  bool background_late_ = false;
  int late_background_frames_ = 0;
  int background_factorisations_ = 0;
  int queued_requests_ = 0;
  std::vector<double> r_, z_, p_, q_;  // CG's vectors
  std::vector<double> snapshot_;       // PETSc: the K to factorise when taken up
  // The rank-one part, and P^-1 g while g and the factorisation P stay the same.
  void apply_raw(const double* b, double* x, int columns, SolveStats& stats);  // P^-1, no rank-one part
  const std::vector<double>& factorised_g(SolveStats& stats);
  void apply_rank_one(double* x, int columns, SolveStats& stats);  // x := (P + c g g')^-1 b from x = P^-1 b
  double rank_one_c_ = 0;
  const double* rank_one_g_ = nullptr;
  std::vector<double> pg_;
  bool pg_current_ = false;
  bool pg_double_ = false;  // pg_ was made with the double factor
  int pg_factorisations_ = -1;
};

}  // namespace fetouch::fem
