// --out naming what the command reads (issue 17: four ways to destroy a user's file): the real
// binary refuses each with exit 2, names the input, and leaves it byte for byte as it was.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

// The command must exit 2 naming `input`, and `input` must be unchanged.
void expect_refused(const std::string& arguments, const fs::path& input) {
  const std::string before = contents(input);
  ASSERT_FALSE(before.empty()) << input;
  const auto r = run_command(fetouch(arguments));
  EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.err;
  EXPECT_NE(r.err.find(input.filename().string()), std::string::npos) << r.err;
  EXPECT_EQ(contents(input), before) << input << " was changed by: " << arguments;
}

TEST(OutputGuard, OutputsNeverReplaceInputs) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_guard_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "trajectories");
  const fs::path source(FETOUCH_SOURCE_DIR);
  fs::copy_file(source / "config/scenes/trajectories/poke_block.csv", dir / "trajectories/poke_block.csv");
  // The block scene with its mesh in a file named as the solve's output would be (NAME.vtu).
  std::string scene = contents(source / "config/scenes/block_press.yaml");
  const std::string generated = "  generate:\n    shape: box\n    size_m: [0.10, 0.08, 0.05]\n    refinements: 2\n";
  ASSERT_NE(scene.find(generated), std::string::npos);
  scene.replace(scene.find(generated), generated.size(), "  file: block_press.vtu\n");
  write(dir / "block_press.yaml", scene);
  fs::copy_file(source / "tests/data/unit_cube.vtu", dir / "block_press.vtu");

  // solve into the folder that holds the scene's mesh under the name it writes.
  expect_refused("solve " + (dir / "block_press.yaml").string() + " --out " + dir.string(), dir / "block_press.vtu");
  // replay over the recording it follows.
  write(dir / "recording.h5", "a recording the user keeps");
  expect_refused("replay " + (source / "config/scenes/block_press.yaml").string() + " --trajectory " +
                     (dir / "recording.h5").string() + " --out " + dir.string(),
                 dir / "recording.h5");
  // ... or over the partial file a replay writes until it completes.
  write(dir / "recording.partial.h5", "a killed run's recording the user replays");
  expect_refused("replay " + (source / "config/scenes/block_press.yaml").string() + " --trajectory " +
                     (dir / "recording.partial.h5").string() + " --out " + dir.string(),
                 dir / "recording.partial.h5");
  // reconstruct over its sweep (refused before the sweep is read).
  write(dir / "sweep.igs.mha", "a sweep");
  write(dir / "calibration.xml", "<PlusConfiguration/>");
  expect_refused("reconstruct " + (dir / "sweep.igs.mha").string() + " --calibration " + (dir / "calibration.xml").string() +
                     " --out " + (dir / "sweep.igs.mha").string(),
                 dir / "sweep.igs.mha");
  // a trajectory written over a scene.
  expect_refused("trajectory poke --at 0.05 0.04 0.05 --out " + (dir / "block_press.yaml").string(), dir / "block_press.yaml");
  // The same files as outputs elsewhere are fine.
  EXPECT_EQ(run_command(fetouch("trajectory poke --at 0.05 0.04 0.05 --out " + (dir / "new.csv").string())).exit_code, 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
