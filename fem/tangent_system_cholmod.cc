// TangentSystem with a factorisation: CHOLMOD called directly on one rank, the background
// factoriser, the schedule on which its factorisations are taken up (shared with the PETSc path, so
// that MPI = serial), and conjugate gradients preconditioned by the current factorisation (CHOLMOD's
// or PETSc's). tangent_system.h says why.
#include <petscksp.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>

#include "fem/background_factoriser.h"
#include "fem/petsc_check.h"
#include "fem/stopwatch.h"
#include "fem/tangent_system.h"

namespace fetouch::fem {

void limit_library_threads();  // tangent_system.cc

void TangentSystem::reset_cholmod() {
  worker_.reset();
  factor_.reset();
  frames_since_request_ = -1;
}

void TangentSystem::set_up_cholmod() {
  const int n = static_cast<int>(rows());
  primed_ = false;
  factor_ = std::make_unique<CholeskyFactor>(n, row_start_.data(), columns_.data());
  worker_ = std::make_unique<Worker>(n, row_start_.data(), columns_.data());
  // FETOUCH_PRECONDITIONER=double: CG preconditioned in double precision, as before (to measure).
  const char* precision = std::getenv("FETOUCH_PRECONDITIONER");
  const bool single = single_precision_preconditioner && factor_->factor_entries() >= single_precision_min_entries &&
                      !(precision && std::string(precision) == "double");
  factor_->single_copy = single, worker_->factor->single_copy = single;
  factorisation_flops_ = factor_->flops();
}

// ---- one rank: CHOLMOD directly, background factorisations ---------------------------------------

bool TangentSystem::factor_cholmod(SolveStats& stats) {
  limit_library_threads();
  const auto start = std::chrono::steady_clock::now();
  const bool ok = factor_->factorise(values_.data());
  stats.factor_s += seconds_since(start);
  if (!ok) {  // not positive definite: PETSc's MUMPS LDL' for this K (leave_cholmod)
    leave_cholmod();
    return false;
  }
  refactor_ = false;
  baseline_iterations_ = -1;
  ++factorisations_;
  stats.refactored = true;
  if (!primed_ && worker_) {
    // The worker's first factorisation is the slowest (CHOLMOD allocates and first touches the
    // factor's memory: 130 ms against 80 ms later on the fetal phantom). Have it make one now, while
    // the session starts, and throw the result away.
    primed_ = true;
    {
      std::lock_guard<std::mutex> lock(worker_->mutex);
      worker_->values = values_;
      worker_->requested = true;
      worker_->done = false;
    }
    worker_->cv.notify_all();
  }
  return true;
}

// K is not positive definite (a tissue past a limit point, or a soft region under a deep press
// whose stiffness, without the liquid's rank-one part, has lost definiteness): MUMPS's LDL'
// factorises it, and the frames solve with that. Only for as long as K stays so: the worker keeps
// factorising by CHOLMOD in the background, and the first of its factorisations that succeeds
// brings the solves back onto CHOLMOD (take_background). Until 2026-11-29 one such K kept the
// session on MUMPS to its end, with every later factorisation made in the frame, not the
// background, and each CG iteration 3-4 times as long (the Leopold exercise's two hands, 8 mm:
// from the 443rd frame of 562 on, frames of 100-275 ms).
void TangentSystem::leave_cholmod() {
  direct_cholmod_ = false;
  push_values();  // PETSc has not seen K's values while CHOLMOD had them
  if (!solver_type_ || std::string(solver_type_) != MATSOLVERMUMPS) create_solver(MATSOLVERMUMPS);
  refactor_ = true;
  ++cholmod_departures_;
}

namespace {
// Real time: the worker 19 nice levels below the requesting (solver) thread, at most 19: at the
// default nice 0 that is 19, a share of about 1.5 % of the core while frames run; under a solver
// raised to -10 (app/realtime_cores.h) it is 9, so that the solver keeps the same lead over it while
// another program's nice-0 load cannot starve it (at 19 it did: with one busy program most
// factorisations came late, 55-74 frames of 200 solved unlike lockstep, against 31-33 at 9-10).
int background_nice() {
  errno = 0;
  const int requester = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
  return errno != 0 ? 19 : std::clamp(requester + 19, -20, 19);
}
}  // namespace

// A factorisation of K as it is now, taken up background_due_frames() frames later. On one rank the
// worker makes it meanwhile; through PETSc (MPI) the snapshot is factorised when it is taken up, so
// that both follow the same schedule and factorise the same matrices (MPI = serial).
void TangentSystem::request_background() {
  if (frames_since_request_ >= 0) return;
  if (!worker_) {
    snapshot_ = values_;
    frames_since_request_ = 0;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(worker_->mutex);
    worker_->pinned = pthread_getaffinity_np(pthread_self(), sizeof worker_->affinity, &worker_->affinity) == 0;
    worker_->nice = deterministic_ ? 0 : background_nice();
    if (worker_->requested && !worker_->done) {
      // The worker is still on its warm-up (the only job it can have here): the request waits behind
      // it on the worker, not in this frame (at 3.6 mm a warm-up takes about a second, and the first
      // press asks during it). The factorisation is of these values either way.
      worker_->queued_values = values_;
      worker_->queued = true;
      ++queued_requests_;
    } else {
      worker_->values = values_;
      worker_->requested = true;
      worker_->done = false;
    }
  }
  worker_->cv.notify_all();
  frames_since_request_ = 0;
}


double TangentSystem::take_background(bool wait) {
  if (frames_since_request_ < 0) return 0;
  const auto start = std::chrono::steady_clock::now();
  if (!worker_) {  // PETSc: factorise the snapshot now, then restore K's current values
    frames_since_request_ = -1;
    values_.swap(snapshot_);
    push_values();
    SolveStats stats;
    const PetscErrorCode code = [&] {
      try {
        factor(stats);
        return PetscErrorCode(0);
      } catch (const std::runtime_error&) {
        return PetscErrorCode(1);
      }
    }();
    values_.swap(snapshot_);
    push_values();
    if (code != 0) refactor_ = true;  // that K was singular: the next solve refactors the current one
    return seconds_since(start);
  }
  std::unique_lock<std::mutex> lock(worker_->mutex);
  if (wait) worker_->cv.wait(lock, [this] { return worker_->done; });
  const double waited = seconds_since(start);
  if (!worker_->done) return waited;
  worker_->requested = worker_->done = false;
  frames_since_request_ = -1;

  if (!worker_->ok) {  // that K was not positive definite: the next solve refactors it by MUMPS
    if (direct_cholmod_) leave_cholmod();
    refactor_ = true;
    return waited;
  }
  std::swap(factor_, worker_->factor);
  direct_cholmod_ = true;  // K is positive definite (again, after leave_cholmod)
  baseline_iterations_ = -1;
  ++factorisations_;
  ++background_factorisations_;
  return waited;
}

bool TangentSystem::background_factorising() const {
  if (!worker_ || frames_since_request_ < 0) return false;
  std::lock_guard<std::mutex> lock(worker_->mutex);
  return worker_->requested && !worker_->done;
}

int TangentSystem::background_due_frames() const {
  if (!(background_flops_per_frame > 0) || !(factorisation_flops_ > 0) || rows() > background_analysed_rows)
    return swap_after_frames;
  const double frames = std::ceil(factorisation_flops_ / background_flops_per_frame);
  return static_cast<int>(std::clamp(frames, 1.0, static_cast<double>(std::max(1, swap_after_frames))));
}

double TangentSystem::begin_frame(bool frame) {
  in_frame_ = frame && method_ == Method::factorisation;
  background_late_ = false;
  if (frames_since_request_ < 0) return 0;
  ++frames_since_request_;
  // Due at the background_due_frames()th frame after the request (or the next solve outside frames),
  // in both modes, so that real time solves what lockstep solves while the worker keeps up. There
  // lockstep waits for it; real time goes on with the old factorisation and takes it up at the
  // first frame after at which it is ready.
  if (frames_since_request_ < background_due_frames() && in_frame_) return 0;
  const double waited = take_background(/*wait=*/deterministic_);
  background_late_ = frames_since_request_ >= 0;
  late_background_frames_ += background_late_;
  return waited;
}

// K factorised now: by CHOLMOD on one rank, by MUMPS's LDL' where CHOLMOD finds K not positive
// definite (leave_cholmod), by PETSc's MUMPS on several ranks.
void TangentSystem::factorise(SolveStats& stats) {
  // Off CHOLMOD since a K that was not positive definite, outside frames (where no worker brings the
  // solves back): CHOLMOD first again.
  if (!direct_cholmod_ && factor_ && !in_frame_) direct_cholmod_ = true;
  if (direct_cholmod_ && factor_cholmod(stats)) return;
  factor(stats);  // PETSc's: MUMPS's LDL' where CHOLMOD has just found K not positive definite
}

// Preconditioned CG on the current K (+ c g g') with the factorisation of an earlier one (+ c g g',
// by Sherman-Morrison); a fresh factorisation solves directly. One loop for CHOLMOD on one rank and
// for PETSc's factorisations (MUMPS on several ranks, or LDL' where K is not positive definite): every
// rank holds K and the whole vectors, so every rank runs the same iterations, and a frame solves
// the same way on any number of ranks to whatever tolerance it asks.
TangentSystem::SolveStats TangentSystem::solve_factorised(const double* b, double* x, double tolerance, bool zero_guess) {
  SolveStats stats;
  const int n = static_cast<int>(rows());
  for (auto* v : {&r_, &z_, &p_, &q_}) v->resize(n);
  if (zero_guess) std::fill(x, x + n, 0.0);
  const auto precondition = [&](const double* in, double* out) {
    apply_factor(in, out);
    apply_rank_one(out, 1, stats);
  };
  const double* g = rank_one_g_;
  const auto apply_k = [&](const double* in, double* out) {  // out = (K + c g g') in
    multiply(in, out);
    if (rank_one_c_ == 0) return;
    const double scale = rank_one_c_ * std::inner_product(g, g + n, in, 0.0);
    for (int i = 0; i < n; ++i) out[i] += scale * g[i];
  };
  const auto direct = [&] {
    const auto start = std::chrono::steady_clock::now();
    const InDouble in_double(in_double_, true);
    precondition(b, x);
    stats.solve_s += seconds_since(start);
    stats.rank_one = rank_one_c_ != 0;
  };
  if (!factored() || refactor_) {
    factorise(stats);
    direct();
    return stats;
  }
  const InDouble in_double(in_double_, tolerance < kSinglePrecisionTolerance);
  if (rank_one_c_ != 0) factorised_g(stats);  // before the clock: timed by itself
  const auto start = std::chrono::steady_clock::now();
  const auto dot = [n](const std::vector<double>& a, const std::vector<double>& c) {
    return std::inner_product(a.begin(), a.begin() + n, c.begin(), 0.0);
  };
  const double b_norm = std::sqrt(std::inner_product(b, b + n, b, 0.0));
  apply_k(x, q_.data());
  for (int i = 0; i < n; ++i) r_[i] = b[i] - q_[i];
  const double target = tolerance * b_norm;
  const int limit = in_frame_ ? max_background_cg_iterations : max_cg_iterations;
  double residual = std::sqrt(dot(r_, r_));
  bool converged = residual <= target;
  int iterations = 0;
  double rz = 0;
  for (; !converged && iterations < limit; ++iterations) {
    precondition(r_.data(), z_.data());
    const double rz_new = dot(r_, z_);
    if (iterations == 0) p_ = z_;
    else
      for (int i = 0; i < n; ++i) p_[i] = z_[i] + (rz_new / rz) * p_[i];
    rz = rz_new;
    apply_k(p_.data(), q_.data());
    const double alpha = rz / dot(p_, q_);
    if (!std::isfinite(alpha)) break;
    for (int i = 0; i < n; ++i) x[i] += alpha * p_[i], r_[i] -= alpha * q_[i];
    residual = std::sqrt(dot(r_, r_));
    converged = residual <= target;
  }
  stats.iterations = iterations;
  stats.solve_s += seconds_since(start);
  if (converged) {
    stats.rank_one = rank_one_c_ != 0;
    // Against the factorisation's own matrix CG takes one iteration: more than
    // refactor_after_iterations means K has drifted from it. (No baseline as for multigrid: a
    // factorisation taken up from the background is already a few frames old, and measuring drift
    // from its first count would let it age without bound.)
    // A looser tolerance takes fewer iterations on the same drift, so their mean rate counts too
    // (refactor_after_iterations at a tolerance of 1e-3 is a rate of 1e-3^(1/refactor_after_iterations)).
    const double rate = iterations > 0 ? std::pow(residual / b_norm, 1.0 / iterations) : 0.0;
    if (iterations > refactor_after_iterations || rate > std::pow(1e-3, 1.0 / refactor_after_iterations)) {
      if (in_frame_) request_background();
      else refactor_ = true;
    }
    return stats;
  }
  // CG on the old factorisation did not get there: factorise K now and solve directly.
  std::fill(x, x + n, 0.0);
  factorise(stats);
  direct();
  return stats;
}

}  // namespace fetouch::fem
