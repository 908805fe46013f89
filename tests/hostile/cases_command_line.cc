// Command-line values: not-a-number, infinite, negative, absurd and malformed option values, unknown
// commands and options, and outputs named over inputs, for every fetouch command.
#include <string>
#include <vector>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

// `args` run in a folder holding the block scene (scene.yaml), a tissue volume (tissue.mha) and
// the unit-cube mesh (cube.vtu); the message names `names`.
Case cli(const std::string& name, const std::string& guards, const std::string& form, std::vector<std::string> args,
         const std::string& names, int exit_code = 2) {
  return {name, "command line", guards, form, [=](const fs::path& dir) {
            write_block_scene(dir);
            write_text(dir / "cube.vtu", read_text(source_dir() / "tests/data/unit_cube.vtu"));
            write_text(dir / "tissue.mha", "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 1 1\n"
                                           "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + std::string(64, '\x40'));
            return Invocation{args, names, exit_code};
          }};
}

}  // namespace

std::vector<Case> command_line_cases() {
  std::vector<Case> c;
  const std::vector<std::string> solve{"solve", "scene.yaml", "--out", "out"};
  const auto with = [](std::vector<std::string> base, const std::vector<std::string>& more) {
    base.insert(base.end(), more.begin(), more.end());
    return base;
  };
  // solve
  c.push_back(cli("SolvePressNaN", "unclear", "non-finite", with(solve, {"--press", "0.05", "0.04", "0.05", "0", "0", "nan"}), "--press"));
  c.push_back(cli("SolvePressInfinite", "unclear", "non-finite", with(solve, {"--press", "0.05", "0.04", "0.05", "0", "0", "-inf"}), "--press"));
  c.push_back(cli("SolvePressOf1e300N", "nonsense", "absurd", with(solve, {"--press", "0.05", "0.04", "0.05", "0", "0", "-1e300"}), "--press"));
  c.push_back(cli("SolvePressFiveValues", "unclear", "wrong shape", with(solve, {"--press", "0.05", "0.04", "0.05", "0", "0"}), "--press"));
  c.push_back(cli("SolvePressWords", "unclear", "wrong shape", with(solve, {"--press", "a", "b", "c", "d", "e", "f"}), "--press"));
  c.push_back(cli("SolveRadiusNaN", "unclear", "non-finite", with(solve, {"--radius", "nan"}), "--radius"));
  c.push_back(cli("SolveRadius10m", "nonsense", "absurd", with(solve, {"--radius", "10"}), "--radius"));
  c.push_back(cli("SolveStepsZero", "unclear", "absurd", with(solve, {"--steps", "0"}), "--steps"));
  c.push_back(cli("SolveStepsABillion", "hang", "absurd", with(solve, {"--steps", "1000000000"}), "--steps"));
  c.push_back(cli("SolvePointNaN", "unclear", "non-finite", with(solve, {"--point", "nan", "0", "0"}), "--point"));
  c.push_back(cli("SolveDurationInfinite", "hang", "non-finite", with(solve, {"--duration", "inf"}), "--duration"));
  c.push_back(cli("SolveOutIsTheScene", "overwrite", "output over input", {"solve", "scene.yaml", "--out", "scene.yaml"}, "scene.yaml"));
  // replay
  c.push_back(cli("ReplayMeshEveryNegative", "unclear", "absurd", {"replay", "scene.yaml", "--mesh-every", "-1"}, "--mesh-every"));
  c.push_back(cli("ReplayMeshEveryNaN", "unclear", "non-finite", {"replay", "scene.yaml", "--mesh-every", "nan"}, "--mesh-every"));
  c.push_back(cli("ReplayUnknownClock", "unclear", "wrong shape", {"replay", "scene.yaml", "--clock", "wallclock"}, "--clock"));
  c.push_back(cli("ReplayOutIsTheScene", "overwrite", "output over input", {"replay", "scene.yaml", "--out", "scene.yaml"}, "scene.yaml"));
  c.push_back(cli("ReplayOutIsTheTrajectoryFolder", "overwrite", "output over input",
                  {"replay", "scene.yaml", "--out", "trajectories/poke_block.csv"}, "poke_block.csv"));
  // mesh
  c.push_back(cli("MeshSizeNaN", "unclear", "non-finite", {"mesh", "tissue.mha", "--size", "nan"}, "--size"));
  c.push_back(cli("MeshSize1e300", "nonsense", "absurd", {"mesh", "tissue.mha", "--size", "1e300"}, "--size"));
  c.push_back(cli("MeshSizeANanometre", "hang", "absurd", {"mesh", "tissue.mha", "--size", "1e-6"}, "--size"));
  c.push_back(cli("MeshThresholdNaN", "unclear", "non-finite", {"mesh", "tissue.mha", "--threshold", "nan"}, "--threshold"));
  c.push_back(cli("MeshSmoothNegative", "unclear", "absurd", {"mesh", "tissue.mha", "--smooth", "-1"}, "--smooth"));
  c.push_back(cli("MeshSmoothInfinite", "unclear", "non-finite", {"mesh", "tissue.mha", "--smooth", "inf"}, "--smooth"));
  c.push_back(cli("MeshRefineNaN", "unclear", "non-finite", {"mesh", "tissue.mha", "--refine", "1", "1", "1", "nan", "1"}, "--refine"));
  c.push_back(cli("MeshPartitionsNegative", "unclear", "absurd", {"mesh", "tissue.mha", "--partitions", "-3"}, "--partitions"));
  c.push_back(cli("MeshLabelsWords", "unclear", "wrong shape", {"mesh", "tissue.mha", "--labels", "uterus"}, "--labels"));
  c.push_back(cli("MeshOutOverTheVolume", "overwrite", "output over input", {"mesh", "tissue.mha", "--out", "tissue.mha"}, "tissue.mha"));
  c.push_back(cli("MeshOutUnknownFormat", "unclear", "name", {"mesh", "tissue.mha", "--out", "tissue.stl"}, "tissue.stl"));
  // phantom, reconstruct
  c.push_back(cli("PhantomSpacingNaN", "unclear", "non-finite", {"phantom", "--spacing", "nan", "--out", "ph"}, "--spacing"));
  c.push_back(cli("PhantomOutIsAFile", "overwrite", "output over input", {"phantom", "--out", "scene.yaml"}, "scene.yaml"));
  c.push_back(cli("ReconstructSpacingNaN", "unclear", "non-finite",
                  {"reconstruct", "tissue.mha", "--calibration", "scene.yaml", "--spacing", "nan"}, "--spacing"));
  // stability
  c.push_back(cli("StabilityK0NaN", "unclear", "non-finite", {"stability", "--k0", "nan"}, "--k0"));
  c.push_back(cli("StabilityKhInfinite", "unclear", "non-finite", {"stability", "--kh", "inf"}, "--kh"));
  c.push_back(cli("StabilityNiNaN", "unclear", "non-finite", {"stability", "--ni", "nan"}, "--ni"));
  c.push_back(cli("StabilityRatioZero", "unclear", "absurd", {"stability", "--ratio", "0"}, "--ratio"));
  c.push_back(cli("StabilityRateNaN", "unclear", "non-finite", {"stability", "--rate-hz", "nan"}, "--rate-hz"));
  c.push_back(cli("StabilityDurationOfAnAeon", "hang", "absurd", {"stability", "--duration", "1e300"}, "--duration"));
  c.push_back(cli("StabilityRangeBackwards", "unclear", "wrong shape", {"stability", "--region", "r", "--kh-range", "5", "1"}, "--kh-range"));
  c.push_back(cli("StabilityRegionBesideTheScene", "valid", "output over input",
                  {"stability", "--region", "scene", "--points", "3"}, "scene", 0));
  // trajectory, render
  c.push_back(cli("TrajectoryAtNaN", "unclear", "non-finite", {"trajectory", "poke", "--at", "nan", "0", "0", "--out", "t.csv"}, "--at"));
  c.push_back(cli("TrajectoryDepth1e300", "nonsense", "absurd", {"trajectory", "poke", "--at", "0", "0", "0", "--depth", "1e300", "--out", "t.csv"}, "--depth"));
  c.push_back(cli("TrajectoryNegativeTimes", "nonsense", "absurd",
                  {"trajectory", "poke", "--at", "0", "0", "0", "--times", "-1", "1", "1", "1", "1", "--out", "t.csv"}, "--times"));
  c.push_back(cli("TrajectoryNormalZero", "nonsense", "absurd", {"trajectory", "poke", "--at", "0", "0", "0", "--normal", "0", "0", "0", "--out", "t.csv"}, "--normal"));
  c.push_back(cli("TrajectoryOverTheScene", "overwrite", "output over input", {"trajectory", "poke", "--at", "0", "0", "0", "--out", "scene.yaml"}, "scene.yaml"));
  c.push_back(cli("RenderOverItsInput", "overwrite", "output over input", {"render", "cube.vtu", "--out", "cube.vtu"}, "cube.vtu"));
  c.push_back(cli("RenderWidthHuge", "unclear", "absurd", {"render", "cube.vtu", "--width", "100000"}, "--width"));
  // Usage.
  c.push_back(cli("UnknownCommand", "unclear", "malformed", {"frobnicate", "scene.yaml"}, "frobnicate"));
  c.push_back(cli("UnknownOption", "unclear", "malformed", {"check", "scene.yaml", "--frobnicate"}, "--frobnicate"));
  c.push_back(cli("MissingOptionValue", "unclear", "truncated", {"solve", "scene.yaml", "--radius"}, "--radius"));
  c.push_back(cli("EmptySceneName", "unclear", "name", {"check", ""}, "scene"));
  c.push_back(cli("NoCommand", "unclear", "truncated", {}, "command"));
  c.push_back(cli("ArgumentOf100KB", "unclear", "huge", {"check", std::string(100000, 's') + ".yaml"}, std::string(40, 's')));
  return c;
}

}  // namespace fetouch::testing::hostile
