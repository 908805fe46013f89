// `fetouch replay` under MPI (issue 6): all ranks step the solver together, rank 0 runs the session.
// On 2 ranks the block poke renders the serial run's forces (the parallel solve differs only by
// round-off: the tolerance is 1e-6 of the force), and its deformed meshes (a piece per rank,
// gathered by PVTUs listed in the PVD) hold the serial mesh's cells and displacements; the default
// scene and the two-user scene render the serial forces too.
#include <gtest/gtest.h>
#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <filesystem>
#include <utility>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"
#include "tests/support/vtk_fields.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

// The largest force of run a's device series, and the largest difference between a's and b's.
template <class Samples>
std::pair<double, double> largest_and_difference(const Samples& a, const Samples& b) {
  double largest = 0, difference = 0;
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) {
    largest = std::max(largest, a[k].force.norm());
    difference = std::max(difference, (a[k].force - b[k].force).norm());
  }
  return {largest, difference};
}

TEST(ReplayMpi, TwoRanksRenderTheSerialForcesAndWriteThePieces) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_mpi_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const std::string args = " --mesh-every 20 " + scene + " --out ";
  const auto serial = run_command(fetouch("replay" + args + (dir / "serial").string()));
  ASSERT_EQ(serial.exit_code, 0) << serial.err;
  const auto parallel = run_command(std::string(FETOUCH_MPIEXEC) + " --allow-run-as-root --oversubscribe -np 2 " +
                                    fetouch("replay" + args + (dir / "parallel").string()));
  ASSERT_EQ(parallel.exit_code, 0) << parallel.err;
  EXPECT_NE(parallel.err.find("on 2 MPI ranks"), std::string::npos) << parallel.err;

  const auto a = app::read_recording(dir / "serial" / "recording.h5").devices.at(0).samples;
  const auto b = app::read_recording(dir / "parallel" / "recording.h5").devices.at(0).samples;
  ASSERT_EQ(a.size(), 3001u);
  ASSERT_EQ(b.size(), a.size());
  const auto [largest, difference] = largest_and_difference(a, b);
  std::printf("largest force %.6f N; largest difference between 1 and 2 ranks %.3g N\n", largest, difference);
  EXPECT_GT(largest, 1.0);
  EXPECT_LE(difference, 1e-6 * largest);

  // Frame 40 (t = 2 s, mid-hold): the serial VTU against the parallel PVTU.
  vtkNew<vtkXMLUnstructuredGridReader> one;
  one->SetFileName((dir / "serial" / "mesh" / "block_press_40.vtu").c_str());
  one->Update();
  vtkNew<vtkXMLPUnstructuredGridReader> pieces;
  pieces->SetFileName((dir / "parallel" / "mesh" / "block_press_0040.pvtu").c_str());
  pieces->Update();
  ASSERT_GT(one->GetOutput()->GetNumberOfCells(), 0);
  EXPECT_EQ(pieces->GetOutput()->GetNumberOfCells(), one->GetOutput()->GetNumberOfCells());
  const double u1 = largest_point_vector(one->GetOutput()), u2 = largest_point_vector(pieces->GetOutput());
  std::printf("largest displacement at 2 s: %.6f mm serial, %.6f mm on 2 ranks\n", 1e3 * u1, 1e3 * u2);
  EXPECT_GT(u1, 0.005);
  EXPECT_NEAR(u2, u1, 1e-6 * u1);
  EXPECT_NE(read_file_text(dir / "parallel" / "block_press.pvd").find("mesh/block_press_0040.pvtu"), std::string::npos);
  fs::remove_all(dir);
}

// Issue 40: on the default scene (the anatomy, its fluid-filled sac) and on the two-user scene
// (two probes, each feeling the other through the condensed coupling) every device's lockstep
// force on 2 ranks is the 1-rank force. One rank factorises by CHOLMOD and two by MUMPS, so their
// solves differ by round-off. Without the accuracy policy (`solver.accuracy: none`: Newton to the
// scene's 1e-8) the runs agree to 1e-9 of the largest force, issue 40's figure: measured 9.7e-13 on
// the default scene and 7.9e-10 / 4.1e-10 on the two users' devices on 2026-12-01; the two users'
// are asserted to 1e-8 (a margin of 1.3 on another machine's round-off is too thin, and Newton to
// 1e-10 left them at 1.7e-9 / 4.1e-10: they are not Newton's). With the policy a frame stops as soon as
// the policy's tolerances (1e-5 m, 1e-3 N, W to 3.2 %) hold, so the round-off decides where
// between them each run stops: measured 1.1e-8 (default scene) and 2.1e-9 / 5.2e-9 (the two
// users' devices) on 2026-11-30, asserted to 1e-7.
void expect_same_forces(const fs::path& scene, std::size_t devices, double relative) {
  SCOPED_TRACE(scene.string());
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_mpi_forces_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string args = " --mesh-every 0 " + scene.string() + " --out ";
  const auto serial = run_command(fetouch("replay" + args + (dir / "serial").string()));
  ASSERT_EQ(serial.exit_code, 0) << serial.err;
  const auto parallel = run_command(std::string(FETOUCH_MPIEXEC) + " --allow-run-as-root --oversubscribe -np 2 " +
                                    fetouch("replay" + args + (dir / "parallel").string()));
  ASSERT_EQ(parallel.exit_code, 0) << parallel.err;
  const auto one = app::read_recording(dir / "serial" / "recording.h5").devices;
  const auto two = app::read_recording(dir / "parallel" / "recording.h5").devices;
  ASSERT_EQ(one.size(), devices);
  ASSERT_EQ(two.size(), devices);
  for (std::size_t d = 0; d < devices; ++d) {
    const auto& a = one[d].samples;
    const auto& b = two[d].samples;
    ASSERT_GT(a.size(), 1000u);
    ASSERT_EQ(b.size(), a.size());
    const auto [largest, difference] = largest_and_difference(a, b);
    std::printf("%s, device %zu: largest force %.6f N; largest difference between 1 and 2 ranks %.3g N (%.3g of it)\n",
                scene.filename().c_str(), d, largest, difference, difference / largest);
    EXPECT_GT(largest, 0.1);
    EXPECT_LE(difference, relative * largest) << "device " << d;
  }
  fs::remove_all(dir);
}

TEST(ReplayMpi, TwoRanksRenderTheSerialForcesOnTheAnatomyAndForTwoUsers) {
  const fs::path scenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  expect_same_forces(scenes / "fetus_phantom.yaml", 1, 1e-7);
  expect_same_forces(scenes / "fetus_two_users.yaml", 2, 1e-7);
}

TEST(ReplayMpi, WithoutTheAccuracyPolicyTwoRanksRenderTheSerialForcesToRoundOff) {
  const fs::path scenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_mpi_exact_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const struct {
    const char* name;
    std::size_t devices;
    double relative;
  } cases[] = {{"fetus_phantom", 1, 1e-9}, {"fetus_two_users", 2, 1e-8}};
  for (const auto& [name, devices, relative] : cases) {
    const fs::path scene = dir / (std::string(name) + ".yaml");
    ASSERT_TRUE(write_scene_variant(scenes / (std::string(name) + ".yaml"), "  linear_solver: auto\n",
                                    "  linear_solver: auto\n  accuracy: none\n", scene));
    expect_same_forces(scene, devices, relative);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
