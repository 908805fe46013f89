// A scene made ready for a session: its tissue (a FemEnvironment with one contact patch per probe,
// on the tissue point nearest the start of the probe's trajectory) and one device per probe. What
// `fetouch replay` and the studies share.
#pragma once

#include <Eigen/Dense>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "config/scene.h"
#include "fem/fem_environment.h"
#include "fem/tissue_model.h"
#include "haptics/devices.h"
#include "haptics/haptic_loop.h"

namespace fetouch::app {

struct SceneRig {
  std::unique_ptr<fem::TissueModel> model;  // its triangulation outlives the solver (declared first)
  std::unique_ptr<fem::FemEnvironment> environment;
  std::vector<std::unique_ptr<haptics::Device>> devices;
  std::vector<std::string> probes;        // the devices' probe names, in order
  std::vector<Eigen::Vector3d> patches;   // each probe's contact patch centre, m
};

// The trajectory a probe's device follows: `first` for probe 0 when given, else the probe's own.
// Throws std::runtime_error naming the probe when it has none.
haptics::Trajectory probe_trajectory(const config::Probe& probe, int index, const std::filesystem::path& first = {});

// The tissue model of `scene` for a session (its mesh must be ready: mesh_scene_volume): each
// frame's solve one time step of the solver's period when the scene lists inertia. What `fetouch
// replay`, `run`, the trainer and the studies build. Throws std::runtime_error naming what is wrong.
std::unique_ptr<fem::TissueModel> build_session_tissue(const config::Scene& scene);

// What to change when the tissue of `scene` fails for a physical reason (fem::PhysicalProblem), as
// "; ..." to append to the reason, or "" when the scene says nothing more.
std::string physical_advice(const config::Scene& scene);

// Builds the session's tissue (build_session_tissue) and the devices.
// Throws std::runtime_error naming what is wrong.
SceneRig build_scene_rig(const config::Scene& scene, const haptics::HapticLoopSettings& settings,
                         const std::filesystem::path& first_trajectory = {});

}  // namespace fetouch::app
