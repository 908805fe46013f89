#include "fem/newton_driver.h"

#include "fem/stopwatch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace fetouch::fem {

using namespace dealii;

NewtonDriver::NewtonDriver(const Discretisation& d, LinearSystem& system, const std::vector<Support>& supports,
                           Vector<double>& u)
    : d_(d), system_(system), supports_(supports), u_(u) {}

bool NewtonDriver::assemble(double lambda, Vector<double>& r, bool tangent, Vector<double>* internal) {
  const auto start = std::chrono::steady_clock::now();
  TangentSystem& k = system_.tangent();
  r = 0;
  if (internal) *internal = 0;
  if (tangent) {
    k.zero();
    tangent_current_ = false;
  }
  const AssemblyState state{u_, static_factor(lambda), lambda};
  AssemblyTarget target{r.begin(), internal ? internal->begin() : nullptr, tangent ? k.values() : nullptr, &system_};
  // This rank's cells first, summed over the ranks (every rank must take the same decision, then hold
  // the same sums); then the terms evaluated whole on every rank.
  term_times.resize(terms_.size());
  const auto timed = [&](std::size_t i) {
    const auto term_start = std::chrono::steady_clock::now();
    const bool ok = terms_[i]->assemble(state, target);
    term_times[i].assembly_s += seconds_since(term_start);
    return ok;
  };
  bool ok = true;
  system_.assembled();  // before the terms: one that fails may have moved g already
  for (std::size_t i = 0; i < terms_.size(); ++i)
    if (terms_[i]->distributed() && ok) ok = timed(i);
  if (!d_.all_ranks(ok)) return assembly_s += seconds_since(start), false;
  d_.sum_over_ranks(r.begin(), r.size());
  if (internal) d_.sum_over_ranks(internal->begin(), internal->size());
  if (tangent) d_.sum_over_ranks(k.values(), k.nonzeros());
  for (std::size_t i = 0; i < terms_.size(); ++i)
    if (!terms_[i]->distributed() && !timed(i)) return assembly_s += seconds_since(start), false;
  if (tangent) {
    tangent_assembled_ = true;
    k.finish(system_.constrained());
    system_.tangent_changed();
    system_.set_rank_one(0, nullptr);
    for (const Term* term : terms_) {
      double c = 0;
      const Vector<double>* g = nullptr;
      if (term->rank_one(c, g)) {
        system_.set_rank_one(c, g);
        break;
      }
    }
    tangent_current_ = true;
  }
  system_.constraints().set_zero(r);
  assembly_s += seconds_since(start);
  return true;
}

const Vector<double>& NewtonDriver::eliminated(const Vector<double>& r) {
  for (const Term* term : terms_)
    if (const double load = term->rank_one_load(); load != 0 && system_.rank_one_g()) {
      shifted_ = r;
      shifted_.add(load, *system_.rank_one_g());
      return shifted_;
    }
  return r;
}

std::vector<double> NewtonDriver::unknowns() const {
  std::vector<double> values;
  for (const Term* term : terms_) values.push_back(term->unknown());
  return values;
}

void NewtonDriver::set_unknowns(const std::vector<double>& values) {
  for (std::size_t i = 0; i < terms_.size(); ++i) terms_[i]->set_unknown(values[i]);
}

// A restoration is a second-order correction: when the tangent it needs cannot be factorised (a
// state past a limit point), the state stays as it is, and the Newton step that follows meets the
// same singular tangent and fails the step cleanly (rolled back, cut), rather than throwing.
void NewtonDriver::restore(std::size_t i, double negligible_force) {
  own(i, [&] {
    try {
      terms_[i]->restore(u_, system_, negligible_force);
    } catch (const std::runtime_error&) {
    }
  });
}

template <class Work>
void NewtonDriver::own(std::size_t i, const Work& work) {
  const auto start = std::chrono::steady_clock::now();
  const int iterations = system_.times.linear_iterations;
  work();
  term_times[i].other_s += seconds_since(start);
  term_times[i].linear_iterations += system_.times.linear_iterations - iterations;
}

// `reference`: the residual norm the tolerance is relative to; negative: the first iteration's.
// `frame`: the solve continues from a converged one, so the accuracy policy and the frame's work
// bound apply.
StepReport NewtonDriver::newton(double lambda, const NewtonSettings& s, double reference,
                                const HandoverError& handover_error, bool frame) {
  StepReport report;
  report.load_factor = lambda;
  system_.apply_supports(supports_, static_factor(lambda), u_);
  Vector<double> r(d_.n_dofs()), du, trial_r(d_.n_dofs());
  bool assembled = false;  // r and the tangent are already those of the current u
  // A frame starts from a linear prediction, which misses a liquid's volume to second order (its
  // stiffness turns that into large forces): the terms restore their own equations first.
  // Under a frame's accuracy policy a restoration that would move the nodal forces by under 1 % of
  // its force tolerance is left out (the policy still judges the residual it leaves).
  const double negligible_force =
      frame && s.position_tolerance_m > 0 && s.force_tolerance_n > 0 ? 1e-2 * s.force_tolerance_n : 0.0;
  if (frame && tangent_assembled_)
    for (std::size_t i = 0; i < terms_.size(); ++i) restore(i, negligible_force);
  for (int it = 0; it <= s.max_iterations; ++it) {
    // Every iteration's residual is assembled with its tangent, a frame's first too: the state the
    // frame hands over is then the tangent's, so the compliance W is this state's even when the
    // linear prediction already meets the policy (until 2026-12-02 such a frame kept the previous
    // frame's tangent, and its W was the previous state's), and the first correction steps with the
    // tangent at the predicted state. (The previous frame's tangent cost the Leopold take 373 Newton
    // iterations against 208, its steps cut by the line search to 0.2-0.6: two hands squeezing the
    // sac change the tangent within a frame.)
    if (!assembled && !assemble(lambda, r, /*tangent=*/true)) {
      report.failure = "an element inverted (J <= 0)";
      return report;
    }
    assembled = false;
    const double norm = r.l2_norm();
    report.residuals.push_back(norm);
    if (!std::isfinite(norm)) {
      report.failure = "the residual is not finite";
      return report;
    }
    if (reference < 0) reference = norm;
    const bool satisfied = std::all_of(terms_.begin(), terms_.end(), [](const Term* t) { return t->satisfied(); });
    // The round-off floor: the residual sums element forces of the order K u, so it cannot fall
    // much below 1e-13 of |K| |u| (mean diagonal times |u|). A solve that starts there (a frame
    // where nothing changed, a body sagging under its weight) is done: Newton cannot improve it,
    // and without this floor a stiff P2 ball under gravity spent 8 cuts x 25 iterations at
    // 1.6e-12 N against an absolute tolerance of 1e-12 N, and failed.
    const double floor = 1e-12 * system_.tangent().diagonal_scale() * u_.l2_norm();
    const bool tight = norm <= s.relative_tolerance * reference || norm <= std::max(s.absolute_tolerance, floor);
    // The right-hand side the step solves for: r with each term's own equation eliminated into it
    // (a cavity's volume law: the force its pressure's mismatch with the law leaves on the wall).
    const Vector<double>& effective = eliminated(r);
    // The accuracy policy: the errors the haptic loop would see, in its units (the caller's estimate
    // of the handed-over points' displacement error, and the largest out-of-balance nodal force),
    // weighed on the effective residual, which holds the terms' own equations too.
    const bool policy = frame && s.position_tolerance_m > 0 && s.force_tolerance_n > 0;
    const double position_error = policy ? handover_error(effective) : 0;
    const bool accurate =
        policy && effective.linfty_norm() <= s.force_tolerance_n && position_error <= s.position_tolerance_m;
    // The frame's work bound: once the residual is down a hundredfold, the remainder goes to the
    // next frame (a state far from equilibrium, whose tangent may be indefinite, is never handed on).
    const bool bounded =
        frame && s.frame_iterations > 0 && it >= s.frame_iterations && norm < 1e-2 * report.residuals.front();
    if ((satisfied && (tight || bounded)) || accurate) {
      report.converged = true;
      report.accurate = !tight && accurate;
      report.carried = !tight && !accurate;
      report.iterations = it;
      return report;
    }
    if (it == s.max_iterations) break;
    // Inexact Newton: far from the solution 1e-3; once the residual has dropped a hundredfold (the
    // quadratic regime), aim the step straight at the convergence tolerance.
    const double quadratic = 0.5 * s.relative_tolerance * reference / norm;
    double eta = std::clamp(norm < 5e-2 * reference ? quadratic : 1e-3, 1e-12, 1e-3);
    // Under a frame's accuracy policy the step need only bring the residual within the policy: the
    // linear residual it may leave is a fifth of the force tolerance (its 2-norm bounds every nodal
    // force) and a fifth of what the handed-over points' error allows, at most a tenth of the
    // effective residual. Aimed at the full tolerance instead, a frame's second iteration took 15-30
    // CG iterations on the stale factorisation to go from 1e-3 to 1e-5 N where the policy asked for
    // 1e-3 N (two hands on the anatomy).
    if (policy) {
      const double force_room = s.force_tolerance_n / effective.l2_norm();
      const double position_room = position_error > 0 ? s.position_tolerance_m / position_error : 1.0;
      eta = std::max(eta, std::min(0.1, 0.2 * std::min(force_room, position_room)));
    }
    const int cg_before = system_.times.linear_iterations;
    try {
      system_.solve(effective, du, eta, /*zero_guess=*/true);
    } catch (const std::runtime_error& e) {  // a singular tangent (past a limit point): the step fails
      report.failure = e.what();
      return report;
    }
    for (std::size_t i = 0; i < terms_.size(); ++i) own(i, [&] { terms_[i]->complete_step(system_, du); });
    // The line search. With an energy (every term conservative) and du a descent direction for it,
    // it follows the energy's slope along the step, g(a) = r(u + a du) . du (Bonet & Wood, Nonlinear
    // Continuum Mechanics for Finite Element Analysis, 2nd ed., section 9.5.3): the full step stands
    // unless it overshoots the energy's minimum along du so that g(1) < -g(0) / 2; then a takes the
    // secant's root. The residual's norm is no merit function here: a good step from rest often
    // raises it tenfold, and halving until it falls costs a dozen iterations a load step. Otherwise
    // (a term without an energy) it halves until the residual's norm decreases. Any step is halved
    // while it inverts an element. The full step is assembled with its tangent, which the next
    // iteration then reuses (one assembly per Newton iteration when the full step is taken).
    // Without the line search the full step is taken whatever its residual.
    const Vector<double> start = u_;
    const std::vector<double> start_unknowns = unknowns();
    const double slope = r * du;
    const bool energy = s.line_search && slope > 0 && conservative_;
    double alpha = 1;
    bool accepted = false;
    const int tries = s.line_search ? 10 : 1;
    for (int b = 0; b < tries && !accepted; ++b) {
      u_ = start;
      u_.add(alpha, du);
      for (std::size_t i = 0; i < terms_.size(); ++i) {
        terms_[i]->take_step(alpha);
        restore(i, negligible_force);  // the step's second-order miss of a term's own equation
      }
      const bool full = b == 0;
      if (!assemble(lambda, trial_r, /*tangent=*/full)) {
        alpha /= 2;
        continue;
      }
      const double trial_slope = energy ? trial_r * du : 0;
      accepted = !s.line_search || b == tries - 1 ||
                 (energy ? trial_slope >= -0.5 * slope : trial_r.l2_norm() < (1 - 1e-4 * alpha) * norm);
      if (accepted && full) {
        r.swap(trial_r);
        assembled = true;
      }
      if (!accepted) alpha = energy ? std::max(0.1 * alpha, alpha * slope / (slope - trial_slope)) : alpha / 2;
    }
    report.steps.push_back({system_.times.linear_iterations - cg_before, accepted ? alpha : 0.0});
    if (!accepted) {
      u_ = start;
      set_unknowns(start_unknowns);
      report.failure = s.line_search ? "the line search found no admissible step" : "the Newton step inverted an element";
      return report;
    }
  }
  report.iterations = s.max_iterations;
  report.failure = "no convergence in " + std::to_string(s.max_iterations) + " Newton iterations";
  return report;
}

// u (converged at load factor `at`) moved to the Lagrange polynomial through the path's states and
// u at `at`, evaluated at `target`.
void NewtonDriver::extrapolate_path(const std::vector<std::pair<double, Vector<double>>>& path, double at,
                                    double target) {
  std::vector<double> factors;
  for (const auto& p : path) factors.push_back(p.first);
  factors.push_back(at);
  const auto weight = [&](std::size_t i) {
    double w = 1;
    for (std::size_t j = 0; j < factors.size(); ++j)
      if (j != i) w *= (target - factors[j]) / (factors[i] - factors[j]);
    return w;
  };
  u_ *= weight(factors.size() - 1);
  for (std::size_t i = 0; i < path.size(); ++i) u_.add(weight(i), path[i].second);
}

SolveReport NewtonDriver::solve(const NewtonSettings& s, const Predictor& predictor, const HandoverError& handover_error) {
  term_times.assign(terms_.size(), SolveReport::TermTime());
  // A haptic frame: a solve that continues from a converged one, with a hand-over error estimate.
  const bool frame = loaded() && static_cast<bool>(handover_error);
  const Vector<double> initial = u_;
  const std::vector<double> initial_unknowns = unknowns();
  assembly_s = 0;
  system_.times = LinearSystem::Times();
  for (std::size_t i = 0; i < terms_.size(); ++i) own(i, [&] { terms_[i]->begin_solve(initial); });
  TangentSystem& tangent = system_.tangent();
  const int factorisations = tangent.factorisations();
  SolveReport report;
  const auto times = [&] {
    report.assembly_s = assembly_s, report.factorisation_s = system_.times.factorisation_s;
    report.solve_s = system_.times.solve_s;
    report.linear_iterations = system_.times.linear_iterations;
    report.factorisations = tangent.factorisations() - factorisations;
  };
  double done = 0, increment = 1.0 / std::max(1, s.load_steps);
  bool predict = static_cast<bool>(predictor);
  // From the second load step on, each starts from the last converged states extrapolated to the
  // new load factor (secant from two, quadratic from three, as CalculiX extrapolates): Newton begins
  // near the answer. Its tolerance stays relative to the load increment's out-of-balance force,
  // estimated from the first step's (dead loads scale with the factor), not to the smaller residual
  // the extrapolation leaves.
  std::vector<std::pair<double, Vector<double>>> path;  // (load factor, converged u), newest last
  double reference_per_load = -1;
  bool extrapolate = true;
  // A snap: past a point where the tissue loses its stability (a wall folding between two probes)
  // the state at a little more load lies far from the last one, and no smaller step avoids the
  // jump; Newton gets there, but in more iterations than a step is given (48 in one step where the
  // steps of 25 each failed, two probes on the anatomy with 4 mm elements under them). So once the
  // cuts are spent on a step that ran out of iterations, that step is tried once more with four
  // times the iterations. Not in a frame, whose time is bounded (it keeps its last good state), nor
  // when cuts are off (`--max-cuts 0` breaks the solver on purpose).
  NewtonSettings longer = s;
  longer.max_iterations = 4 * s.max_iterations;
  bool snap = false, snap_tried = false;
  while (done < 1 - 1e-12) {
    const double target = std::min(1.0, done + increment);
    Vector<double> last_good = u_;
    const std::vector<double> last_good_unknowns = unknowns();
    const bool extrapolated = extrapolate && !predict && !path.empty() && reference_per_load > 0;
    if (extrapolated) extrapolate_path(path, done, target);
    const double reference = predict ? predictor(u_) : extrapolated ? reference_per_load * (target - done) : -1;
    StepReport step = newton(target, snap ? longer : s, reference, handover_error, frame && s.load_steps <= 1);
    const bool exhausted = !step.converged && step.iterations >= (snap ? longer : s).max_iterations;
    snap = false;
    report.carried = report.carried || step.carried;
    report.total_iterations += static_cast<int>(step.residuals.size()) - 1;
    const bool ok = step.converged;
    if (ok && !predict && reference_per_load < 0 && !step.residuals.empty())
      reference_per_load = step.residuals.front() / (target - done);
    report.steps.push_back(step);
    if (ok) {
      if (path.size() == 2) path.erase(path.begin());
      path.emplace_back(done, std::move(last_good));
      done = target;
      predict = false;
      extrapolate = true;
      continue;
    }
    u_ = last_good;  // roll back the step
    set_unknowns(last_good_unknowns);
    tangent_current_ = false;
    if (predict || extrapolated) {  // retry the same step from the last converged state
      predict = false;
      extrapolate = false;
      continue;
    }
    tangent.refactor_next();  // the retry starts from a state the factorisation may not fit
    if (report.cuts == s.max_cuts && exhausted && !snap_tried && !frame && s.max_cuts > 0) {
      snap = snap_tried = true;  // the same step, once, with the longer budget
      continue;
    }
    if (++report.cuts > s.max_cuts) {
      u_ = initial;  // and the whole solve: the state stays the last converged one
      set_unknowns(initial_unknowns);
      report.failure = "load step at factor " + std::to_string(target) + " failed after " + std::to_string(s.max_cuts) +
                       " cuts: " + step.failure;
      times();
      return report;
    }
    increment /= 2;
  }
  report.converged = true;
  times();
  static_done_ = 1;
  for (std::size_t i = 0; i < terms_.size(); ++i) own(i, [&] { terms_[i]->accept(u_); });
  return report;
}

}  // namespace fetouch::fem
