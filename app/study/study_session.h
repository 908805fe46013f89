// One measured lockstep session of a scene, for the studies (`fetouch study`): the scene's probes
// replayed against its tissue exactly as `fetouch replay` does (app/scene_rig.h, app/session.h),
// with each frame's solve timed and described, and every force sent kept.
#pragma once

#include <Eigen/Dense>

#include <string>
#include <utility>
#include <vector>

#include "config/scene.h"
#include "haptics/haptic_loop.h"

namespace fetouch::app {

struct StudyFrame {
  double time_s = 0;            // when the frame's samples were taken
  double solve_s = 0;           // the environment's answer, measured around it
  int newton_iterations = 0, linear_iterations = 0, cuts = 0;
  bool converged = true;
  std::vector<double> felt_n_per_m;  // per probe: n' (W_pp)^-1 n, the stiffness felt along the normal
};

struct StudyRun {
  unsigned int dofs = 0;
  long cells = 0;
  long ticks = 0;
  double period_s = 1e-3;
  std::vector<std::vector<Eigen::Vector3d>> forces;  // per probe, per tick: the force sent
  std::vector<StudyFrame> frames;
  // Summed over the frames: each term's assembly, and the phases of the solves.
  std::vector<std::pair<std::string, double>> term_assembly_s;
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
