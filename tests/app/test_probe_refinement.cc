// meshing.refine: {around_probes: true}: the refinement ball made from the scene's trajectories, against
// its closed form: the centre of the bounding box of every replayed or operated probe's path, and
// half the box's diagonal plus the largest such probe's radius. Probes without a path (the mouse,
// a PHANTOM) add nothing; a scene without any is refused with its name.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>


#include "app/mesh_pipeline.h"
#include "app/scene_mesh.h"
#include "tests/support/scratch_dir.h"

namespace fetouch::app {
namespace {

using fetouch::testing::ScratchDir;

namespace fs = std::filesystem;

fs::path write_path(const ScratchDir& scratch, const std::string& name, const std::string& rows) {
  const fs::path file = scratch / name;
  std::ofstream(file) << "# t, x, y, z\n" << rows;
  return file;
}

config::Probe probe(const std::string& name, config::DeviceType type, const fs::path& trajectory, double radius) {
  config::Probe p;
  p.name = name, p.device.type = type, p.device.trajectory = trajectory, p.radius_m = radius;
  return p;
}

TEST(ProbeRefinement, TheBallHoldsEveryProbesPathWidenedByItsRadius) {
  config::Scene scene;
  scene.source = "/scenes/two_hands.yaml";
  scene.mesh.source = config::MeshSource::phantom;
  scene.mesh.meshing.refine_around_probes = true;
  scene.mesh.meshing.refine_size_m = 0.003;
  const ScratchDir scratch("fetouch_refine");
  const fs::path a = write_path(scratch, "a.csv", "0, 0, 0, 0.06\n1, 0.01, 0.02, 0.04\n");
  const fs::path b = write_path(scratch, "b.csv", "0, -0.01, 0, 0.05\n0.5, -0.01, 0.01, 0.05\n");
  scene.probes.push_back(probe("left", config::DeviceType::replay, a, 0.005));
  scene.probes.push_back(probe("right", config::DeviceType::operator_model, b, 0.008));
  scene.probes.push_back(probe("mouse", config::DeviceType::mouse, {}, 0.02));  // no path: not counted
  const config::MeshSpec spec = resolved_mesh_spec(scene);
  ASSERT_TRUE(spec.meshing.refine_center_m.has_value());
  // Box [-0.01, 0.01] x [0, 0.02] x [0.04, 0.06]: centre (0, 0.01, 0.05), half diagonal 0.01 sqrt(3).
  const auto& c = *spec.meshing.refine_center_m;
  EXPECT_NEAR(c[0], 0.0, 1e-15);
  EXPECT_NEAR(c[1], 0.01, 1e-15);
  EXPECT_NEAR(c[2], 0.05, 1e-15);
  EXPECT_NEAR(spec.meshing.refine_radius_m, 0.01 * std::sqrt(3.0) + 0.008, 1e-15);
  EXPECT_DOUBLE_EQ(spec.meshing.refine_size_m, 0.003);
  EXPECT_NE(meshing_sizes_text(spec.meshing).find("3 mm within"), std::string::npos) << meshing_sizes_text(spec.meshing);

  scene.mesh.meshing.refine_around_probes = false;  // not asked: unchanged
  EXPECT_FALSE(resolved_mesh_spec(scene).meshing.refine_center_m.has_value());

  scene.mesh.meshing.refine_around_probes = true;
  scene.probes.resize(1);
  scene.probes[0].device.trajectory = write_path(scratch, "bad.csv", "0, 0, 0, nan\n1, 0, 0, 0\n");
  try {
    resolved_mesh_spec(scene);
    ADD_FAILURE() << "an unreadable path is refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("two_hands.yaml"), std::string::npos) << e.what();
  }
  scene.probes[0] = probe("mouse", config::DeviceType::mouse, {}, 0.02);
  try {
    resolved_mesh_spec(scene);
    ADD_FAILURE() << "no path to refine around is refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no probe has a trajectory"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fetouch::app
