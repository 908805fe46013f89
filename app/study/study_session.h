// One measured lockstep session of a scene, for the studies (`fetouch study`): the scene's probes
// replayed against its tissue exactly as `fetouch replay` does (app/scene_rig.h, app/session.h),
// with each frame's solve timed and described, and every force sent kept.
#pragma once

#include <Eigen/Dense>

#include <string>
#include <vector>

#include "config/scene.h"
#include "haptics/haptic_loop.h"

namespace fetouch::app {

// A term's own time (fem::SolveReport::TermTime): its assembly, and its other own work (a cavity's
// restorations and step completions, solves with the factorisation) with their linear iterations.
struct StudyTermTime {
  std::string name;
  double assembly_s = 0, other_s = 0;
  long linear_iterations = 0;
  double own_s() const { return assembly_s + other_s; }
};

struct StudyFrame {
  double time_s = 0;            // when the frame's samples were taken
  double solve_s = 0;           // the environment's answer, measured around it
  int newton_iterations = 0, linear_iterations = 0, cuts = 0, factorisations = 0;
  bool background = false;  // a background factorisation was under way (fem::SolveReport::background)
  bool converged = true;
  // The solve's phases, s: every term's assembly (each term's own below), factorisation, linear solves.
  double assembly_s = 0, factorisation_s = 0, linear_solve_s = 0;
  std::vector<StudyTermTime> terms;  // in StudyRun::terms' order
  // The condensed compliance handed over after the solve (fem::ComplianceTimes): its time, s, its
  // linear iterations and factorisations, and whether its columns were solved again.
  double compliance_s = 0;
  int compliance_linear_iterations = 0, compliance_factorisations = 0;
  bool compliance_refined = false;
  std::vector<double> felt_n_per_m;  // per probe: n' (W_pp)^-1 n, the stiffness felt along the normal
};

struct StudyRun {
  unsigned int dofs = 0;
  long cells = 0;
  long ticks = 0;
  double period_s = 1e-3;
  std::vector<std::vector<Eigen::Vector3d>> forces;  // per probe, per tick: the force sent
  std::vector<StudyFrame> frames;
  // Summed over the frames: each term's own time, and the phases of the solves.
  std::vector<StudyTermTime> terms;
  double assembly_s = 0, factorisation_s = 0, linear_solve_s = 0;
  long newton_failures = 0;
  double wall_s = 0;  // the whole run, the tissue's set-up included
};

struct StudyRunSettings {
  long max_ticks = -1;   // < 0: the whole trajectory
  int threads = 1;       // assembly threads (1 or 2)
};

// Runs the scene (its mesh must be ready: mesh_scene_volume) with these loop settings. Throws
// std::runtime_error naming what is wrong.
StudyRun run_study_session(const config::Scene& scene, const haptics::HapticLoopSettings& loop,
                           const StudyRunSettings& settings);

}  // namespace fetouch::app
