// Newton's method over whatever terms it is given (term.h): find u with r(u) = sum of the terms'
// f_ext - f_int = 0 on the free dofs, the supports prescribed, the loads applied in steps
// lambda = 1/n, 2/n, ..., 1 from the last converged solve's (a solve continues from the previous
// frame's state and loads: a warm start).
//
// Each iteration solves K du = r with the consistent tangent to a tolerance that shrinks with the
// residual (inexact Newton), then a line search: when every term has an energy it scales a step that
// overshoots the energy's minimum along it (its slope r.du), otherwise it halves the step until the
// residual decreases; a step that inverts an element is halved either way (without the line search
// it fails the load step). From the second load step on, Newton starts from the converged path
// extrapolated to the new load factor. A step whose Newton fails is rolled back to the last converged state and retried (first without the extrapolation, then
// with half the increment, down to a minimum); a solve that fails altogether leaves the state it
// started from. It names no effect.
#pragma once

#include <algorithm>

#include <deal.II/lac/vector.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fem/discretisation.h"
#include "fem/linear_system.h"
#include "fem/term.h"

namespace fetouch::fem {

struct NewtonSettings {
  double relative_tolerance = 1e-8;  // on the residual norm, against the step's first residual
  double absolute_tolerance = 1e-12; // N
  int max_iterations = 25;
  int load_steps = 1;
  int max_cuts = 8;                  // a step can be halved this many times
  bool line_search = true;           // false: every full Newton step is taken
  // The accuracy that matters to the haptic loop, for a haptic frame (a solve that continues from a
  // converged one, with an estimate of the error of what it hands over): it stops once the
  // linearised error of every handed-over point is below position_tolerance_m and the largest out-of-balance nodal force is below force_tolerance_n,
  // whatever the relative residual (0: off; the residual tolerances alone).
  double position_tolerance_m = 0;
  double force_tolerance_n = 0;
  // A frame's work bound: after this many Newton iterations a frame that has reduced its residual a
  // hundredfold stops there and the next frame carries the remainder (its residual includes it).
  // 0: no bound.
  // Counted in iterations, not seconds, so that lockstep runs stay reproducible.
  int frame_iterations = 0;
};

struct StepReport {
  double load_factor = 0;
  int iterations = 0;
  std::vector<double> residuals;  // per Newton iteration
  // Per Newton step solved: the CG iterations of its linear solve and the line search's step length
  // (1: the full step; 0: the search found none, and the step failed).
  struct Step {
    int cg = 0;
    double length = 0;
  };
  std::vector<Step> steps;
  bool converged = false;
  bool accurate = false;          // stopped by the accuracy policy
  bool carried = false;           // stopped by the frame's work bound, the remainder carried
  std::string failure;            // why not, empty if converged
};

struct SolveReport {
  bool converged = false;
  bool carried = false;  // the frame's work bound stopped it short of its tolerance
  int total_iterations = 0;
  int cuts = 0;
  std::vector<StepReport> steps;  // every attempt, the failed ones included
  std::string failure;
  // Time per phase, seconds: assembly (residual and tangent), factorisation, linear solves.
  double assembly_s = 0, factorisation_s = 0, solve_s = 0;
  double total_s = 0;  // the whole solve (QuasiStaticSolver::solve): the phases and everything between them
  int linear_iterations = 0;  // CG iterations preconditioned by an earlier factorisation
  int factorisations = 0;
  // A background factorisation was under way during the solve (the worker shares the machine).
  bool background = false;
  // One was taken up at the solve's start (its wait is in factorisation_s: background_wait_s).
  bool background_taken = false;
  double background_wait_s = 0;
  // Real time: the one lockstep takes up here was not ready, and the solve went on without it
  // (TangentSystem::background_late).
  bool background_late = false;
  // Each term's own time: its assembly (part of assembly_s) and the rest of its own work (a cavity's
  // restorations and step completions, which solve with the factorisation: part of solve_s), with
  // the linear iterations that work took.
  struct TermTime {
    std::string name;
    double assembly_s = 0, other_s = 0;
    int linear_iterations = 0;
  };
  std::vector<TermTime> terms;
};

class NewtonDriver {
 public:
  NewtonDriver(const Discretisation& discretisation, LinearSystem& system, const std::vector<Support>& supports,
               dealii::Vector<double>& u);
  void set_terms(std::vector<Term*> terms) {
    terms_ = std::move(terms);
    conservative_ = std::all_of(terms_.begin(), terms_.end(), [](const Term* t) { return t->conservative(); });
  }
  const std::vector<Term*>& terms() const { return terms_; }

  // r = f_ext - f_int at load factor lambda (constrained entries zero) and, with `tangent`, K;
  // `internal`, if given, receives f_int - f_ext of the body on every dof (reactions). False when a
  // term rejects the state.
  bool assemble(double lambda, dealii::Vector<double>& r, bool tangent, dealii::Vector<double>* internal = nullptr);

  // Moves u before the first step's Newton (a linear prediction); returns the residual norm the
  // tolerance is relative to, or a negative number for the first iteration's.
  using Predictor = std::function<double(dealii::Vector<double>& u)>;
  // The accuracy policy's error estimate for a residual: the largest linearised displacement error
  // of the points handed to the haptic loop, m (NewtonSettings::position_tolerance_m); null: no
  // estimate, the policy is off.
  using HandoverError = std::function<double(const dealii::Vector<double>& r)>;
  // Each term's own time over the last solve, in the terms' order (SolveReport::terms, unnamed).
  std::vector<SolveReport::TermTime> term_times;
  SolveReport solve(const NewtonSettings& settings, const Predictor& predictor = {},
                    const HandoverError& handover_error = {});

  bool tangent_current() const { return tangent_current_; }
  // The tangent no longer is the current state's; `values_lost`: the matrix no longer holds a
  // tangent of any state either (new supports).
  void invalidate_tangent(bool values_lost = false) {
    tangent_current_ = false;
    if (values_lost) tangent_assembled_ = false;
  }
  // Loads already applied: 0 before the first converged solve, 1 after.
  bool loaded() const { return static_done_ == 1; }
  double assembly_s = 0;  // accumulated; the caller resets it

 private:
  double static_factor(double lambda) const { return static_done_ + lambda * (1 - static_done_); }
  StepReport newton(double lambda, const NewtonSettings& s, double reference, const HandoverError& handover_error,
                    bool frame);
  // r plus the rank-one load of the term that has one (its own equation eliminated): the step's
  // right-hand side; r itself when no term has one. Valid until the next call.
  const dealii::Vector<double>& eliminated(const dealii::Vector<double>& r);
  // term i's restore(u), a factorisation that fails leaving u as it was.
  void restore(std::size_t i, double negligible_force);
  // Runs `work` of term i's own (not its assembly), timed against it.
  template <class Work>
  void own(std::size_t i, const Work& work);
  std::vector<double> unknowns() const;
  void set_unknowns(const std::vector<double>& values);

  const Discretisation& d_;
  LinearSystem& system_;
  const std::vector<Support>& supports_;
  dealii::Vector<double>& u_;
  void extrapolate_path(const std::vector<std::pair<double, dealii::Vector<double>>>& path, double at,
                        double target);
  std::vector<Term*> terms_;
  dealii::Vector<double> shifted_;  // r with a term's rank-one load
  bool conservative_ = true;  // every term has an energy: the line search follows it
  bool tangent_current_ = false;
  bool tangent_assembled_ = false;  // the matrix holds the tangent of some recent state
  double static_done_ = 0;
};

}  // namespace fetouch::fem
