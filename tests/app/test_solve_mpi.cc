// `mpirun -np 2 fetouch solve` against the serial `fetouch solve` on the shipped block scene (P1)
// and a P2 test scene: the same displacements, reactions and probe displacements to the Newton
// tolerance, the same Newton iterations, and the summary saying 2 ranks. Label mpi.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

YAML::Node solve(const std::string& launcher, const std::string& arguments) {
  const auto r = run_command(launcher + fetouch("solve --json " + arguments));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return YAML::Load(r.out);
}

void expect_same_solve(const std::string& arguments) {
  const YAML::Node serial = solve("", arguments);
  const YAML::Node parallel = solve(FETOUCH_MPIEXEC " --allow-run-as-root --oversubscribe -np 2 ", arguments);
  ASSERT_TRUE(serial["converged"].as<bool>());
  ASSERT_TRUE(parallel["converged"].as<bool>());
  EXPECT_EQ(serial["ranks"].as<int>(), 1);
  EXPECT_EQ(parallel["ranks"].as<int>(), 2);
  EXPECT_EQ(serial["newton_iterations"].as<int>(), parallel["newton_iterations"].as<int>());
  const auto close = [](const YAML::Node& a, const YAML::Node& b, double scale) {
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(a[d].as<double>(), b[d].as<double>(), 1e-8 * scale);
  };
  const double u = serial["max_displacement_m"].as<double>();
  close(serial["points"][0]["displacement_m"], parallel["points"][0]["displacement_m"], u);
  if (serial["probes"].size() > 0) close(serial["probes"][0]["displacement_m"], parallel["probes"][0]["displacement_m"], u);
  for (const auto& region : serial["reactions_n"]) {
    const std::string name = region.first.as<std::string>();
    close(region.second, parallel["reactions_n"][name], 1.0);
  }
}

TEST(SolveMpi, TwoRanksReproduceTheSerialBlockPress) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("fetouch_mpi_solve_" + std::to_string(::getpid()));
  expect_same_solve("--press 0.05 0.04 0.05 0 0 -0.3 --point 0.05 0.04 0.03 --out " + dir.string() + " " FETOUCH_SOURCE_DIR
                    "/config/scenes/block_press.yaml");
  expect_same_solve("--point 0.05 0.04 0.02 --out " + dir.string() + " " FETOUCH_TEST_DATA_DIR "/data/block_gravity.yaml");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
