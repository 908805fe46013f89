#include "fem/fem_environment.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "fem/physical_problem.h"
#include "fem/stopwatch.h"

namespace fetouch::fem {

FemEnvironment::FemEnvironment(std::unique_ptr<QuasiStaticSolver> solver, const NewtonSettings& newton)
    : solver_(std::move(solver)), newton_(newton) {
  if (!solver_ || solver_->patches() < 1) throw std::invalid_argument("FemEnvironment: the solver needs a contact patch per contact");
}

void FemEnvironment::describe(haptics::EnvironmentUpdate& out) {
  const int m = contacts();
  out.frames.resize(m);
  for (int c = 0; c < m; ++c) {
    const dealii::Point<3> center = solver_->patch_center(c);
    const dealii::Tensor<1, 3> u = solver_->patch_displacement(c), n = solver_->patch_normal(c);
    for (int d = 0; d < 3; ++d) {
      out.frames[c].point(d) = center[d] + u[d];
      out.frames[c].normal(d) = n[d];
    }
    out.frames[c].curvature.setZero();
  }
  const dealii::FullMatrix<double> w = solver_->compliance();
  out.compliance.resize(3 * m, 3 * m);
  for (int a = 0; a < 3 * m; ++a)
    for (int b = 0; b < 3 * m; ++b) out.compliance(a, b) = 0.5 * (w(a, b) + w(b, a));  // exact up to round-off
  out.damping.resize(0, 0);
}

void FemEnvironment::initial(haptics::EnvironmentUpdate& out) {
  const SolveReport report = solver_->solve(newton_);
  if (!report.converged)
    throw PhysicalProblem("the tissue finds no rest state under its supports and static loads (its weight, tractions, a cavity's pressure) "
                          "before any probe touches it: " + report.failure);
  describe(out);
  out.status = {};
  out.frame = -1;
  last_good_ = out;
}

void FemEnvironment::solve(const std::vector<haptics::ContactSample>& samples, long frame,
                           haptics::EnvironmentUpdate& out) {
  const auto start = std::chrono::steady_clock::now();
  const int late_before = solver_->late_background_frames();  // the patch moves' solves count too
  if (anchors_.size() != samples.size()) {
    anchors_.clear(), applied_.assign(samples.size(), Eigen::Vector3d::Zero());
    for (const auto& sample : samples) anchors_.push_back(sample.position);
  }
  for (int c = 0; c < contacts() && follow_; ++c) {
    // The probe's own motion since its patch was placed, in the patch's tangent plane; the patch
    // moves by it on the reference surface. Measured from the device alone: an offset from the
    // patch's deformed point would feed the deformation back (tried: on a slope, the patch walked
    // 16 mm down it in three frames and Newton failed).
    const Eigen::Vector3d& x = samples[c].position;
    if (!x.allFinite()) continue;
    // The normal the last answer described (the solver holds that state still).
    const Eigen::Vector3d& n = last_good_.frames[c].normal;
    const Eigen::Vector3d along = (x - anchors_[c]) - (x - anchors_[c]).dot(n) * n;
    const dealii::Tensor<1, 3> motion({along.x(), along.y(), along.z()});
    const double radius = solver_->patch_radius(c);
    if (motion.norm() <= 0.25 * radius) continue;
    // A move of more than a radius (a probe that jumped across the surface in one frame) carries
    // the patch's whole load to a place the state knows nothing of, which no load step can cut
    // down: the patch slides there in steps of half a radius, the tissue solved under its force
    // after each, and stays at the last place a step reached if one fails.
    // A patch that carries no force, and is given none (the probe in the air), has no load to
    // carry: it goes there at once (a hand crossing the abdomen between presses).
    const bool unloaded = applied_[c].norm() == 0 && !(samples[c].force.norm() > 0);
    const int steps = unloaded ? 1 : static_cast<int>(std::ceil(motion.norm() / (0.5 * radius)));
    const dealii::Point<3> from = solver_->patch_center(c);
    try {
      dealii::Point<3> reached = from;
      for (int k = 1; k <= steps; ++k) {
        const dealii::Point<3> next = solver_->boundary_point_nearest(from + (double(k) / steps) * motion, /*deformed=*/false);
        solver_->move_contact_patch(c, next);
        if (k < steps && !solver_->solve(newton_).converged) {
          solver_->move_contact_patch(c, reached);  // where the rolled-back state has it
          break;
        }
        reached = next;
      }
      anchors_[c] = x;
      ++patch_moves_;
    } catch (const std::invalid_argument&) {
      // No boundary within the radius there (cannot happen for a boundary point): stay.
    }
  }
  for (int c = 0; c < contacts(); ++c) {
    dealii::Tensor<1, 3> force;
    for (int d = 0; d < 3; ++d) force[d] = samples[c].force(d);
    solver_->set_patch_force(c, force);
    applied_[c] = samples[c].force.allFinite() ? samples[c].force : Eigen::Vector3d::Zero();
  }
  last_report_ = solver_->solve(newton_);
  const SolveReport& report = last_report_;
  std::string failure = report.failure;
  if (report.converged) {
    describe(out);
    // The haptic side needs W symmetric positive definite (its gains are chosen for W^-1); past a
    // limit point of the tissue it is not: the frame is then reported failed and the last good kept.
    if (Eigen::LLT<Eigen::MatrixXd>(out.compliance).info() != Eigen::Success)
      failure = "the condensed compliance is not positive definite (the tissue is past a limit point)";
  }
  if (report.converged && failure.empty()) {
    out.status = {};
    last_good_ = out;
  } else {
    out = last_good_;
    out.status = {};
    out.status.converged = false;
    out.status.message = failure;
  }
  out.status.iterations = report.total_iterations;
  if (!report.steps.empty() && !report.steps.back().residuals.empty())
    out.status.residual = report.steps.back().residuals.back();
  out.status.seconds = seconds_since(start);
  out.status.differs_from_lockstep = solver_->late_background_frames() != late_before;
  out.frame = frame;
  // FETOUCH_TRACE_FRAMES=1: where each frame's time went, one line per frame on standard error.
  static const bool trace = std::getenv("FETOUCH_TRACE_FRAMES") != nullptr;
  if (trace) {
    std::string residuals;
    for (const StepReport& step : report.steps)
      for (const double r : step.residuals) {
        char text[24];
        std::snprintf(text, sizeof text, "%.3g", r);  // residuals span 1e-14 to 1e3 N
        residuals += (residuals.empty() ? "" : " ") + std::string(text);
      }
    // Each Newton step: its CG iterations and the line search's step length ("12 cg x 0.31").
    std::string steps;
    for (const StepReport& load_step : report.steps)
      for (const StepReport::Step& step : load_step.steps) {
        char text[40];
        std::snprintf(text, sizeof text, "%d cg x %.2g", step.cg, step.length);
        steps += (steps.empty() ? "" : ", ") + std::string(text);
      }
    std::fprintf(stderr, "frame %ld: %.1f ms; %s; patch moves %ld; residuals %s%s%s\n", frame, 1e3 * out.status.seconds,
                 describe_frame(report, solver_->last_compliance_times()).c_str(), patch_moves_, residuals.c_str(),
                 steps.empty() ? "" : "; steps ", steps.c_str());
  }

}

}  // namespace fetouch::fem
