#include "app/scene_rig.h"

#include <cstdio>
#include <stdexcept>
#include <utility>

#include "app/log.h"
#include "app/recording.h"
#include "app/scene_devices.h"

namespace fetouch::app {

haptics::Trajectory probe_trajectory(const config::Probe& probe, int index, const std::filesystem::path& first) {
  const std::filesystem::path file = (index == 0 && !first.empty()) ? first : probe.device.trajectory;
  if (file.empty()) throw std::runtime_error("probe " + probe.name + " has no trajectory (device.trajectory)");
  return read_probe_trajectory(file, probe.name, index);
}

std::unique_ptr<fem::TissueModel> build_session_tissue(const config::Scene& scene) {
  log::info() << "building the tissue model of " << scene.name;
  std::unique_ptr<fem::TissueModel> model = fem::build_tissue_model(scene);
  if (model->pieces > 1)
    log::warning() << scene.name << ": the mesh falls into " << model->pieces
                   << " separate pieces (each held by its supports); they do not touch each other";
  // Inertia (and damping): each frame's solve is one time step of the solver's period.
  if (const auto dynamics = fem::scene_dynamics(scene, model.get())) model->solver->enable_dynamics(*dynamics);
  return model;
}

SceneRig build_scene_rig(const config::Scene& scene, const haptics::HapticLoopSettings& settings,
                         const std::filesystem::path& first_trajectory) {
  SceneRig rig;
  rig.model = build_session_tissue(scene);
  fem::TissueModel* model = rig.model.get();
  for (int p = 0; p < static_cast<int>(scene.probes.size()); ++p) {
    const config::Probe& probe = scene.probes[p];
    const haptics::Trajectory path = probe_trajectory(probe, p, first_trajectory);
    const Eigen::Vector3d& start = path.positions_m.front();
    const dealii::Point<3> touch = model->solver->boundary_point_nearest(dealii::Point<3>(start[0], start[1], start[2]));
    log::detail() << "probe " << probe.name << ": contact patch at (" << touch << ") m";
    rig.patches.emplace_back(touch[0], touch[1], touch[2]);
    model->solver->add_contact_patch(touch, probe.radius_m);
    rig.devices.push_back(make_device(probe, scene, settings, &path));
    rig.probes.push_back(probe.name);
  }
  rig.environment = std::make_unique<fem::FemEnvironment>(std::move(model->solver), model->newton);
  return rig;
}

std::string physical_advice(const config::Scene& scene) {
  bool svk = scene.material.model == config::MaterialModel::saint_venant_kirchhoff;
  for (const auto& region : scene.materials) svk = svk || region.material.model == config::MaterialModel::saint_venant_kirchhoff;
  bool loaded = scene.effects.has(config::Effect::gravity);
  for (const config::BoundaryRegion& region : scene.boundary) loaded = loaded || region.type == config::BoundaryType::traction;
  if (scene.effects.has(config::Effect::cavity) && scene.effects.cavity_law == config::PressureVolumeLaw::isothermal_gas &&
      scene.effects.cavity_initial_pressure_pa > 0) {
    double modulus = scene.material.youngs_modulus_pa;
    if (scene.material.model == config::MaterialModel::mooney_rivlin)
      modulus = 6 * (scene.material.c10_pa + scene.material.c01_pa);
    char text[320];
    std::snprintf(text, sizeof text,
                  "; the cavity's gas starts at %.4g Pa and inflates a wall of modulus %.4g Pa: an elastic shell has a "
                  "largest pressure it can hold (an inflation limit point, of the order of its modulus times its "
                  "thickness over its radius), past which it has no rest state: a lower initial pressure or a stiffer wall",
                  scene.effects.cavity_initial_pressure_pa, modulus);
    return text;
  }
  if (svk && loaded)
    return "; Saint Venant-Kirchhoff softens in compression (a fibre's stress peaks when it is compressed by 42 %, "
           "stretch 1/sqrt(3), and falls after), so a soft block collapses under its own weight or a traction: use "
           "neo_hookean, or a stiffer material";
  if (loaded) return "; the tissue may be too soft for its weight or tractions: a stiffer material or more supports";
  return "";
}

}  // namespace fetouch::app
