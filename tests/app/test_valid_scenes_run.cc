// Valid scenes that used to fail at run time or pass in silence (issue 41), through the real binary:
// a probe smaller than the faces under it touches; a tissue nothing holds, one that cannot carry its
// weight and a load that diverges each say why in one line with exit 1 ("the work failed"), never a
// silent zero force and never exit 2 (bad input) for a valid file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kBlock = fs::path(FETOUCH_SOURCE_DIR) / "config/scenes/block_press.yaml";
const std::string kPoke = (fs::path(FETOUCH_SOURCE_DIR) / "config/scenes/trajectories/poke_block.csv").string();

double max_force(const fs::path& summary) {
  std::smatch m;
  const std::string text = read_file_text(summary);
  const std::regex key(R"("max_force_n":\s*([-+0-9.eE]+))");
  return std::regex_search(text, m, key) ? std::stod(m[1]) : -1;
}

// A 1 mm probe on block_press, whose top faces are 25 to 6 mm across at refinements 0 to 2: it was
// refused ("no boundary surface within the radius"); it now touches and feels a force.
TEST(ValidScenesRun, AOneMillimetreProbeTouchesEveryMesh) {
  const ScratchDir scratch("fetouch_valid");
  for (const int refinements : {0, 1, 2}) {
    const fs::path dir = scratch.folder("small_probe_" + std::to_string(refinements));
    const fs::path scene = dir / "scene.yaml";
    ASSERT_TRUE(write_scene_variant(kBlock, "refinements: 2", "refinements: " + std::to_string(refinements), scene));
    std::string text = read_file_text(scene);
    text.replace(text.find("radius_m: 0.005"), 15, "radius_m: 0.001");
    std::ofstream(scene) << text;
    const CommandResult r = run_command(fetouch("-q replay " + scene.string() + " --mesh-every 0 --out " + (dir / "out").string()));
    EXPECT_EQ(r.exit_code, 0) << refinements << ": " << r.err;
    EXPECT_GT(max_force(dir / "out" / "summary.json"), 0.01) << refinements;
  }
  for (const std::string shape : {"{shape: ball, radius_m: 0.03, refinements: 1}",
                                  "{shape: shell, radius_m: 0.03, inner_radius_m: 0.02, refinements: 1}"}) {
    const fs::path dir = scratch.folder(shape.substr(8, 4));
    const std::string trajectory = (dir / "poke.csv").string();
    ASSERT_EQ(run_command(fetouch("trajectory poke --at 0 0 0.03 --normal 0 0 1 --depth 0.004 --out " + trajectory)).exit_code, 0);
    std::ofstream(dir / "scene.yaml")
        << "name: round\nunits: SI\nmesh:\n  generate: " << shape
        << "\nmaterial: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.45}\neffects: [contact]\n"
           "boundary:\n  - {name: base, type: fixed, select: {box: {min: [-0.03, -0.03, -0.031], max: [0.03, 0.03, -0.01]}}}\n"
           "probes:\n  - {name: tool, radius_m: 0.001, device: {type: replay, trajectory: "
        << trajectory << "}}\n";
    const CommandResult r =
        run_command(fetouch("-q replay " + (dir / "scene.yaml").string() + " --mesh-every 0 --out " + (dir / "out").string()));
    EXPECT_EQ(r.exit_code, 0) << shape << ": " << r.err;
    EXPECT_GT(max_force(dir / "out" / "summary.json"), 0.01) << shape;
  }
}

// A block on a frictionless table alone: nothing stops it sliding. `check` says so, and a replay
// fails with the motions named instead of replaying a tissue that floats away (max force 0 N).
TEST(ValidScenesRun, ATissueNothingHoldsIsNamedByCheckAndByTheReplay) {
  const ScratchDir scratch("fetouch_valid");
  const fs::path dir = scratch.folder("floating");
  const fs::path scene = dir / "scene.yaml";
  ASSERT_TRUE(write_scene_variant(kBlock, "select: {physical_group: zmin}", "components: [z]\n    select: {physical_group: zmin}", scene));
  CommandResult r = run_command(fetouch("check " + scene.string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("not held against translation along x, translation along y and rotation about z"), std::string::npos) << r.err;
  r = run_command(fetouch("-q replay " + scene.string() + " --out " + (dir / "out").string()));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("error: the work failed: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not held"), std::string::npos) << r.err;
}

// A soft Saint Venant-Kirchhoff block under its own weight (rho g H = 515 Pa on E = 100 Pa) collapses:
// the model softens in compression. Exit 1 with that reason, not exit 2.
TEST(ValidScenesRun, ATissueThatCannotCarryItsWeightSaysWhy) {
  const ScratchDir scratch("fetouch_valid");
  const fs::path dir = scratch.folder("collapse");
  const fs::path scene = dir / "scene.yaml";
  ASSERT_TRUE(write_scene_variant(kBlock, "effects:\n  - contact", "effects:\n  - contact\n  - gravity", scene));
  std::string text = read_file_text(scene);
  text.replace(text.find("model: neo_hookean"), 18, "model: saint_venant_kirchhoff");
  text.replace(text.find("youngs_modulus_pa: 5000"), 23, "youngs_modulus_pa: 100");
  std::ofstream(scene) << text;
  const CommandResult r = run_command(fetouch("-q replay " + scene.string() + " --out " + (dir / "out").string()));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("error: the work failed: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no rest state"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Saint Venant-Kirchhoff softens in compression"), std::string::npos) << r.err;
}

// `fetouch solve` with an absurd gravity: the solve fails, and standard error says so (it said
// nothing, exit 1), also under --json where standard output is the report alone.
TEST(ValidScenesRun, AFailedSolveIsSaidOnStandardError) {
  const ScratchDir scratch("fetouch_valid");
  const fs::path dir = scratch.folder("gravity");
  const fs::path scene = dir / "scene.yaml";
  ASSERT_TRUE(write_scene_variant(kBlock, "effects:\n  - contact", "effects:\n  - contact\n  - gravity: {acceleration_m_per_s2: [0, 0, -1.0e+300]}", scene));
  const CommandResult r = run_command(fetouch("-q solve " + scene.string() + " --json --out " + (dir / "out").string()));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("error: the work failed: "), std::string::npos) << r.err;
}

}  // namespace
}  // namespace fetouch::testing
