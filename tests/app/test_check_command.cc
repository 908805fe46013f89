// `fetouch check` on the shipped scenes and on every broken scene of tests/config/broken.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "tests/support/broken_scene.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

const std::string kScenes = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes";

TEST(CheckCommand, AcceptsEveryShippedScene) {
  // The spine scene meshes the shared ultrasound data beside the repository: left out without it.
  const bool shared = std::filesystem::exists(std::string(FETOUCH_SOURCE_DIR) + "/../shared/data/ultrasound");
  std::string scenes;
  for (const auto& entry : std::filesystem::directory_iterator(kScenes))
    if (entry.path().extension() == ".yaml" && (shared || entry.path().filename() != "spine_phantom.yaml"))
      scenes += " " + entry.path().string();
  const auto r = run_command(fetouch("check" + scenes));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(": valid"), std::string::npos);
}

TEST(CheckCommand, JsonReportDescribesTheScene) {
  const auto r = run_command(fetouch("check --json " + kScenes + "/block_press.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node report = YAML::Load(r.out);
  const YAML::Node scene = report["scenes"][0];
  EXPECT_TRUE(scene["valid"].as<bool>());
  EXPECT_EQ(scene["ratio"].as<int>(), 50);
  // The block is 0.10 x 0.08 x 0.05 m and its tetrahedra tile it exactly.
  EXPECT_NEAR(scene["mesh"]["volume_m3"].as<double>(), 0.10 * 0.08 * 0.05, 1e-15);
  EXPECT_TRUE(scene["mesh"]["simplex"].as<bool>());
}

// The default scene ships with a refinement ball around the probe's path: check prints the ball (its
// value is checked against the closed form in tests/app/test_probe_refinement.cc).
TEST(CheckCommand, ReportsTheRefinementBallAroundTheProbes) {
  const auto r = run_command(fetouch("check --no-mesh " + kScenes + "/fetus_phantom.yaml"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("4 mm within"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("around the probes' paths"), std::string::npos) << r.out;
}

class BrokenSceneCli : public ::testing::TestWithParam<std::filesystem::path> {};

TEST_P(BrokenSceneCli, RejectedWithFileLineAndKey) {
  const BrokenSceneExpectation expected = read_expectation(GetParam());
  const std::string file = expected.file.string();
  const auto r = run_command(fetouch("check " + file));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::string where = file + ":" + std::to_string(expected.line) + ":";
  // One line of stderr carries the position, the key and the explanation.
  bool found = false;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);)
    found = found || (line.rfind(where, 0) == 0 && line.find(" error: ") != std::string::npos &&
                      line.find(expected.key.empty() ? "" : expected.key + ": ") != std::string::npos &&
                      line.find(expected.message) != std::string::npos);
  EXPECT_TRUE(found) << "expected " << where << " ... " << expected.key << ": ..."
                     << expected.message << "\ngot:\n" << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;

  const auto json = run_command(fetouch("check --json " + file));
  EXPECT_EQ(json.exit_code, 2);
  const YAML::Node errors = YAML::Load(json.out)["scenes"][0]["errors"];
  ASSERT_TRUE(errors.IsSequence()) << json.out;
  bool in_json = false;
  for (const auto& e : errors)
    in_json = in_json || (e["line"].as<int>() == expected.line && e["key"].as<std::string>() == expected.key);
  EXPECT_TRUE(in_json) << json.out;
}

INSTANTIATE_TEST_SUITE_P(Files, BrokenSceneCli, ::testing::ValuesIn(broken_scene_files()),
                         [](const auto& param_info) { return scene_test_name(param_info.param); });

TEST(CheckCommand, SeveralFilesOneBad) {
  const auto r = run_command(fetouch("check " + kScenes + "/block_press.yaml " +
                                     std::string(FETOUCH_TEST_DATA_DIR) +
                                     "/config/broken/poisson_half.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("block_press.yaml: valid"), std::string::npos);
  EXPECT_NE(r.err.find("1 of 2 scene files rejected"), std::string::npos) << r.err;
}

TEST(CheckCommand, MissingSceneFile) {
  const auto r = run_command(fetouch("check /nonexistent/scene.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/nonexistent/scene.yaml"), std::string::npos);
  EXPECT_NE(r.err.find("no such scene file"), std::string::npos);
}

}  // namespace
}  // namespace fetouch::testing
