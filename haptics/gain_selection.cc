#include "haptics/gain_selection.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "haptics/scalar_loop.h"

namespace fetouch::haptics {

namespace {

struct Mode {
  double stiffness, damping;
};

// The modes of K and B, and the scale samples: everything the robust radius iterates over.
class UncertaintySet {
 public:
  UncertaintySet(const GainProblem& problem, const GainSelectionOptions& options) : problem_(problem) {
    if (options.hand) hand_ = ScalarHand(*options.hand, options.period_s), with_hand_ = true;
    const Eigen::MatrixXd& k = problem.stiffness;
    const auto m = k.rows();
    if (m == 0 || k.cols() != m) throw std::invalid_argument("gain selection: the stiffness must be square and non-empty");
    if (!k.isApprox(k.transpose(), 1e-9)) throw std::invalid_argument("gain selection: the stiffness must be symmetric");
    if (problem.damping.size() && (problem.damping.rows() != m || problem.damping.cols() != m))
      throw std::invalid_argument("gain selection: the damping must have the stiffness's size");
    if (!(options.margin >= 0 && options.margin < 1))
      throw std::invalid_argument("gain selection: the margin must lie in [0, 1)");
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (k + k.transpose()));
    for (Eigen::Index i = 0; i < m; ++i) {
      const double lambda = eigen.eigenvalues()(i);
      if (!(lambda > 0)) throw std::invalid_argument("gain selection: the stiffness must be positive definite");
      const Eigen::VectorXd v = eigen.eigenvectors().col(i);
      const double b = problem.damping.size() ? v.dot(problem.damping * v) : 0.0;
      modes_.push_back({lambda, std::max(b, 0.0)});
    }
    const int samples = std::max(options.scale_samples, options.margin > 0 ? 2 : 1);
    for (int j = 0; j < samples; ++j)
      scales_.push_back(samples == 1 ? 1.0 : 1 - options.margin + 2 * options.margin * j / (samples - 1));
  }

  double smallest_stiffness() const { return modes_.front().stiffness; }  // eigenvalues ascend

  bool with_hand() const { return with_hand_; }

  // Which loops a radius covers: the device held still, the design hand's, or both (the larger).
  enum class Loops { still, hand, both };

  // The robust radius: the largest over every (mode, scale). A search only needs to know whether a
  // trial beats the best so far, so the scan stops as soon as one loop exceeds `cutoff`, starting
  // from the (mode, scale) that was worst last time: most rejected trials cost one evaluation.
  double radius(const LocalModelGains& gains, int& evaluations,
                double cutoff = std::numeric_limits<double>::infinity(), Loops loops = Loops::both) const {
    ScalarLoop loop;
    loop.local_model = problem_.local_model;
    loop.hold = problem_.hold;
    loop.ratio = problem_.ratio;
    loop.gains = gains;
    double worst = 0;
    const int count = static_cast<int>(modes_.size() * scales_.size());
    const int first = worst_index_;
    for (int e = 0; e < count; ++e) {
      const int index = (first + e) % count;
      const Mode& mode = modes_[index / scales_.size()];
      loop.damping = mode.damping;
      loop.compliance = 1.0 / mode.stiffness;
      loop.stiffness = scales_[index % scales_.size()] * mode.stiffness;
      double r = loops == Loops::hand ? 0.0 : scalar_spectral_radius(loop);
      ++evaluations;
      if (with_hand_ && loops != Loops::still && !(r > cutoff)) r = std::max(r, hand_spectral_radius(loop, hand_));
      if (std::isnan(r)) r = std::numeric_limits<double>::infinity();
      if (r > worst) worst = r, worst_index_ = index;
      if (worst > cutoff) break;
    }
    return worst;
  }

 private:
  const GainProblem& problem_;
  std::vector<Mode> modes_;
  std::vector<double> scales_;
  mutable int worst_index_ = 0;
  ScalarHand hand_;
  bool with_hand_ = false;
};

// P and Smith: the stiffest Kh whose radius is at most the settle radius.
GainSelection select_proportional(const UncertaintySet& set, const GainProblem& problem,
                                  const GainSelectionOptions& options) {
  GainSelection best;
  const double lambda = set.smallest_stiffness();
  const double top = has_predictor(problem.local_model) ? 20.0 : 3.0;  // Kh / lambda_min
  constexpr int grid = 24;
  using Loops = UncertaintySet::Loops;
  // Accepted: the radius without the hand at most settle_radius, and with the design hand (if any)
  // at most hand_settle_radius.
  const auto accept = [&](double kh) {
    if (set.radius({kh, 0}, best.evaluations, options.settle_radius, Loops::still) > options.settle_radius) return false;
    return !set.with_hand() ||
           set.radius({kh, 0}, best.evaluations, options.hand_settle_radius, Loops::hand) <= options.hand_settle_radius;
  };
  double best_radius = std::numeric_limits<double>::infinity(), best_kh = 0;
  double accepted = -1, rejected_above = -1;
  // Log-spaced from 0.01 lambda_min to `top` lambda_min, scanned downwards: the first accepted
  // gain is the stiffest on the grid.
  for (int g = grid - 1; g >= 0; --g) {
    const double kh = lambda * 0.01 * std::pow(top / 0.01, static_cast<double>(g) / (grid - 1));
    if (accept(kh)) {
      accepted = kh;
      break;
    }
    const double r = set.radius({kh, 0}, best.evaluations, best_radius);
    if (r < best_radius) best_radius = r, best_kh = kh;
    rejected_above = kh;
  }
  if (accepted > 0) {
    double low = accepted, high = rejected_above;
    if (high > 0)
      for (int it = 0; it < 12; ++it) {  // bisect the crossing to 0.1 % or so
        const double mid = std::sqrt(low * high);
        (accept(mid) ? low : high) = mid;
      }
    best.gains = {low, 0};
  } else {
    best.gains = {best_kh, 0};
  }
  best.spectral_radius = set.radius(best.gains, best.evaluations);
  best.stable = best.spectral_radius < 1;
  return best;
}

// PI and PI + Smith: minimise the radius over (Kh, N I): a coarse grid, then a compass search.
GainSelection select_integral(const UncertaintySet& set, const GainProblem& problem,
                              const LocalModelGains* start) {
  GainSelection best;
  const double lambda = set.smallest_stiffness(), n = problem.ratio;
  constexpr int grid = 9;
  double best_radius = std::numeric_limits<double>::infinity();
  double kh = 0, ni = 0;
  double step = lambda / grid;  // the same for Kh and N I
  if (start && start->proportional > 0 && start->integral > 0) {
    // Warm start from the previous frame's gains: the stiffness moves little between frames.
    kh = start->proportional, ni = start->integral * n;
    best_radius = set.radius(*start, best.evaluations);
    step = lambda / (4 * grid);
  }
  if (!(best_radius < 1)) {  // cold start, or the previous gains are no longer stable
    best_radius = std::numeric_limits<double>::infinity();
    step = lambda / grid;
    for (int a = 0; a < grid; ++a)
      for (int b = 0; b < grid; ++b) {
        const double trial_kh = lambda * 3.0 * (a + 0.5) / grid, trial_ni = lambda * 2.0 * (b + 0.5) / grid;
        const double r = set.radius({trial_kh, trial_ni / n}, best.evaluations, best_radius);
        if (r < best_radius) best_radius = r, kh = trial_kh, ni = trial_ni;
      }
  }
  // Pattern search with axis, diagonal and knight's moves: the radius has sharp valleys along
  // double-root curves (the deadbeat point sits where two of them cross), which axis moves alone
  // cannot follow.
  const double moves[16][2] = {{1, 0},  {-1, 0},  {0, 1},  {0, -1}, {1, 1},  {-1, -1}, {1, -1},  {-1, 1},
                               {2, 1},  {-2, -1}, {1, 2},  {-1, -2}, {2, -1}, {-2, 1},  {1, -2},  {-1, 2}};
  // Opportunistic polling: the move that succeeded last is tried first, the first improvement is
  // taken, and the step halves when no move improves by more than a part in 1e9.
  int first = 0;
  for (int it = 0; it < 100 && step > 1e-4 * lambda; ++it) {
    bool moved = false;
    for (int m = 0; m < 16 && !moved; ++m) {
      const int move = (first + m) % 16;
      const double trial_kh = kh + moves[move][0] * step, trial_ni = ni + moves[move][1] * step;
      if (trial_kh <= 0 || trial_ni <= 0) continue;
      const double r = set.radius({trial_kh, trial_ni / n}, best.evaluations, best_radius);
      if (r < best_radius * (1 - 1e-9)) best_radius = r, kh = trial_kh, ni = trial_ni, moved = true, first = move;
    }
    if (!moved) step /= 2;
  }
  best.gains = {kh, ni / n};
  best.spectral_radius = best_radius;
  best.stable = best_radius < 1;
  return best;
}

}  // namespace

GainSelection select_gains(const GainProblem& problem, const GainSelectionOptions& options,
                           const LocalModelGains* start) {
  if (problem.ratio < 1) throw std::invalid_argument("gain selection: the ratio N must be at least 1");
  const UncertaintySet set(problem, options);
  GainSelection selection = has_integrator(problem.local_model) ? select_integral(set, problem, start)
                                                                : select_proportional(set, problem, options);
  if (set.with_hand())
    selection.hand_spectral_radius = set.radius(selection.gains, selection.evaluations,
                                                std::numeric_limits<double>::infinity(), UncertaintySet::Loops::hand);
  return selection;
}

double robust_spectral_radius(const GainProblem& problem, const LocalModelGains& gains,
                              const GainSelectionOptions& options) {
  const UncertaintySet set(problem, options);
  int evaluations = 0;
  return set.radius(gains, evaluations);
}

}  // namespace fetouch::haptics
