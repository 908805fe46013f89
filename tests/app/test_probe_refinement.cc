// meshing.refine: {around_probes: true}: the refinement balls made from the scene's trajectories, against
// their closed form: one per replayed or operated probe, at the centre of the bounding box of its
// path, of radius half the box's diagonal plus the probe's radius (two users at the two sides of the
// uterus get a ball each, not one ball over the whole of it). Probes without a path (the mouse, a
// PHANTOM) add nothing; a scene without any is refused with its name.
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

TEST(ProbeRefinement, EachProbesPathGetsABallWidenedByItsRadius) {
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
  ASSERT_EQ(spec.meshing.refine_balls.size(), 2u);
  // left: box [0, 0.01] x [0, 0.02] x [0.04, 0.06], centre (0.005, 0.01, 0.05), half diagonal
  // sqrt(0.01^2 + 0.02^2 + 0.02^2) / 2 = 0.015, widened by its 5 mm.
  const auto& left = spec.meshing.refine_balls[0];
  EXPECT_NEAR(left.center_m[0], 0.005, 1e-15);
  EXPECT_NEAR(left.center_m[1], 0.01, 1e-15);
  EXPECT_NEAR(left.center_m[2], 0.05, 1e-15);
  EXPECT_NEAR(left.radius_m, 0.015 + 0.005, 1e-15);
  // right: the segment from (-0.01, 0, 0.05) to (-0.01, 0.01, 0.05), widened by its 8 mm.
  const auto& right = spec.meshing.refine_balls[1];
  EXPECT_NEAR(right.center_m[0], -0.01, 1e-15);
  EXPECT_NEAR(right.center_m[1], 0.005, 1e-15);
  EXPECT_NEAR(right.center_m[2], 0.05, 1e-15);
  EXPECT_NEAR(right.radius_m, 0.005 + 0.008, 1e-15);
  EXPECT_DOUBLE_EQ(spec.meshing.refine_size_m, 0.003);
  const std::string text = meshing_sizes_text(spec.meshing);
  EXPECT_NE(text.find("3 mm within 20 mm of (5 mm, 10 mm, 50 mm), 13 mm of (-10 mm, 5 mm, 50 mm) around each probe's path"),
            std::string::npos)
      << text;

  scene.mesh.meshing.refine_around_probes = false;  // not asked: unchanged
  EXPECT_TRUE(resolved_mesh_spec(scene).meshing.refine_balls.empty());

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
