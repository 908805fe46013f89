#include "app/study/study_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "app/scene_rig.h"
#include "app/session.h"
#include "fem/fem_environment.h"

namespace fetouch::app {

namespace {

using Clock = std::chrono::steady_clock;

// The tissue with a stopwatch: each frame's answer timed and described as it passes.
class MeasuredEnvironment final : public haptics::Environment {
 public:
  MeasuredEnvironment(fem::FemEnvironment& inner, double frame_period_s, StudyRun& run)
      : inner_(inner), frame_period_s_(frame_period_s), run_(run) {}
  int contacts() const override { return inner_.contacts(); }
  void initial(haptics::EnvironmentUpdate& out) override { inner_.initial(out); }
  void solve(const std::vector<haptics::ContactSample>& samples, long frame, haptics::EnvironmentUpdate& out) override {
    const auto start = Clock::now();
    inner_.solve(samples, frame, out);
    StudyFrame f;
    f.solve_s = std::chrono::duration<double>(Clock::now() - start).count();
    f.time_s = (frame + 1) * frame_period_s_;
    const fem::SolveReport& report = inner_.last_report();
    f.newton_iterations = report.total_iterations;
    f.linear_iterations = report.linear_iterations;
    f.cuts = report.cuts, f.factorisations = report.factorisations, f.background = report.background;
    const fem::ComplianceTimes& compliance = inner_.solver().last_compliance_times();
    f.compliance_s = compliance.assembly_s + compliance.factorisation_s + compliance.solves_s;
    f.compliance_linear_iterations = compliance.linear_iterations, f.compliance_factorisations = compliance.factorisations;
    f.compliance_refined = compliance.refined;
    f.converged = out.status.converged;
    for (int c = 0; c < contacts(); ++c) {
      const Eigen::Matrix3d w = out.compliance.block<3, 3>(3 * c, 3 * c);
      const Eigen::Vector3d n = out.frames[static_cast<std::size_t>(c)].normal;
      f.felt_n_per_m.push_back(n.dot(w.ldlt().solve(n)));
    }
    f.assembly_s = report.assembly_s, f.factorisation_s = report.factorisation_s, f.linear_solve_s = report.solve_s;
    if (!out.status.converged) ++run_.newton_failures;
    run_.assembly_s += report.assembly_s, run_.factorisation_s += report.factorisation_s;
    run_.linear_solve_s += report.solve_s;
    for (const fem::SolveReport::TermTime& t : report.terms) {
      auto it = std::find_if(run_.terms.begin(), run_.terms.end(), [&t](const StudyTermTime& s) { return s.name == t.name; });
      if (it == run_.terms.end()) it = run_.terms.insert(it, StudyTermTime{t.name});
      it->assembly_s += t.assembly_s, it->other_s += t.other_s, it->linear_iterations += t.linear_iterations;
      const auto at = static_cast<std::size_t>(it - run_.terms.begin());
      if (f.terms.size() <= at) f.terms.resize(at + 1);
      f.terms[at] = StudyTermTime{t.name, t.assembly_s, t.other_s, t.linear_iterations};
    }
    run_.frames.push_back(std::move(f));
  }

 private:
  fem::FemEnvironment& inner_;
  double frame_period_s_;
  StudyRun& run_;
};

}  // namespace

StudyRun run_study_session(const config::Scene& scene, const haptics::HapticLoopSettings& loop,
                           const StudyRunSettings& settings) {
  const auto start = Clock::now();
  StudyRun run;
  SceneRig rig = build_scene_rig(scene, loop);
  fem::FemEnvironment& tissue = *rig.environment;
  tissue.solver().set_assembly_threads(settings.threads >= 2 ? 2 : 1);
  run.dofs = tissue.solver().dofs();
  run.cells = static_cast<long>(rig.model->triangulation.n_active_cells());
  run.period_s = loop.period_s;
  MeasuredEnvironment measured(tissue, loop.ratio * loop.period_s, run);
  SessionSettings session;
  session.loop = loop;
  session.probes = rig.probes;
  session.keep_forces = true;
  session.max_ticks = settings.max_ticks;
  SessionSummary summary = run_lockstep(measured, rig.devices, session);
  run.ticks = summary.ticks;
  run.forces = std::move(summary.forces);
  run.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return run;
}

}  // namespace fetouch::app
