// `fetouch solve`, the real binary on real scenes, against global equilibrium (the supports' reaction
// balances every load applied) and with its VTU read back by VTK as ParaView would.
#include <gtest/gtest.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_solve_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

// Gravity (rho g V = 1050 x 9.81 x 4e-4 m^3 = 4.1202 N down) and a dead-load traction of 20 Pa on
// the 0.08 x 0.05 m face x = 0.1 (0.08 N along x): the base must push back exactly that.
TEST(SolveCommand, SupportReactionBalancesGravityAndTraction) {
  const fs::path dir = scratch("gravity");
  const auto r = run_command(fetouch("solve --json --out " + dir.string() + " " + FETOUCH_TEST_DATA_DIR + "/data/block_gravity.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  ASSERT_TRUE(j["converged"].as<bool>());
  const auto base = j["reactions_n"]["base"];
  const double weight = 1050 * 9.81 * 0.1 * 0.08 * 0.05, pull = 20 * 0.08 * 0.05;
  EXPECT_NEAR(base[0].as<double>(), -pull, 1e-6 * weight);
  EXPECT_NEAR(base[1].as<double>(), 0, 1e-6 * weight);
  EXPECT_NEAR(base[2].as<double>(), weight, 1e-6 * weight);
  EXPECT_GT(j["min_jacobian"].as<double>(), 0.5);
  // The summary file says the same as stdout.
  EXPECT_EQ(YAML::LoadFile((dir / "summary.json").string())["reactions_n"]["base"][2].as<double>(), base[2].as<double>());
  fs::remove_all(dir);
}

// A water balloon (tests/data/water_balloon.yaml) pressed at the top with 0.5 N: the equator band
// takes the 0.5 N (the water's pressure on a closed wall has no net force), the water's pressure
// rises while its volume stays within p/K of the start, and the bottom pole moves out (down).
TEST(SolveCommand, WaterBalloonKeepsItsVolumeAndPushesBack) {
  const fs::path dir = scratch("balloon");
  const auto r = run_command(fetouch("solve --json --radius 0.015 --press 0 0 0.05 0 0 -0.5 --point 0 0 -0.05 --out " +
                                     dir.string() + " " + FETOUCH_TEST_DATA_DIR + "/data/water_balloon.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  ASSERT_TRUE(j["converged"].as<bool>());
  EXPECT_NEAR(j["reactions_n"]["equator"][2].as<double>(), 0.5, 1e-6);
  const double p = j["cavity"]["pressure_pa"].as<double>();
  const double v = j["cavity"]["volume_m3"].as<double>(), v0 = j["cavity"]["reference_volume_m3"].as<double>();
  EXPECT_GT(p, 0.0);
  EXPECT_NEAR(v / v0 - 1, -p / 2.2e9, 1e-10);
  EXPECT_LT(j["points"][0]["displacement_m"][2].as<double>(), 0.0);
  fs::remove_all(dir);
}

// A scene with inertia (tests/data/block_drop.yaml: the weight acts suddenly, Newmark, no damping)
// is a dynamic load case: one VTU per time step listed in the PVD with its time, and a time series in
// the summary that starts at rest, overshoots the static sag of the same scene without inertia and
// swings back above it (an undamped step response rings about the static state).
TEST(SolveCommand, InertiaMakesADynamicLoadCaseWithATimeSeries) {
  const fs::path dir = scratch("drop");
  const std::string scene = std::string(FETOUCH_TEST_DATA_DIR) + "/data/block_drop.yaml";
  const auto r = run_command(fetouch("solve --json --duration 0.1 --out " + dir.string() + " " + scene));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  const YAML::Node steps = j["dynamic"]["time_steps"];
  ASSERT_EQ(steps.size(), 40u);  // 0.1 s at 400 Hz
  EXPECT_NEAR(j["dynamic"]["time_step_s"].as<double>(), 0.0025, 1e-12);
  // The same block without inertia, for its static sag.
  std::ifstream in(scene);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), line;
  std::istringstream lines(text);
  std::ofstream out(dir / "static.yaml");
  while (std::getline(lines, line))
    if (line.find("inertia") == std::string::npos) out << line << "\n";
  out.close();
  const auto st = run_command(fetouch("solve --json --out " + (dir / "static").string() + " " + (dir / "static.yaml").string()));
  ASSERT_EQ(st.exit_code, 0) << st.err;
  const double sag = YAML::Load(st.out)["max_displacement_m"].as<double>();
  double peak = 0, trough_after_peak = 1e9;
  int peak_at = 0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const double u = steps[k]["max_displacement_m"].as<double>();
    if (u > peak) peak = u, peak_at = static_cast<int>(k);
  }
  for (std::size_t k = peak_at; k < steps.size(); ++k) trough_after_peak = std::min(trough_after_peak, steps[k]["max_displacement_m"].as<double>());
  std::printf("static sag %.3f mm; dynamic: first step %.3f mm, peak %.3f mm at %.4f s, then down to %.3f mm\n", 1e3 * sag,
              1e3 * steps[0]["max_displacement_m"].as<double>(), 1e3 * peak, steps[peak_at]["t_s"].as<double>(),
              1e3 * trough_after_peak);
  EXPECT_LT(steps[0]["max_displacement_m"].as<double>(), 0.1 * sag);  // from rest
  EXPECT_GT(peak, 1.3 * sag);
  EXPECT_LT(trough_after_peak, 0.7 * sag);
  // ParaView's time series: VTK reads every step's file.
  std::ifstream pvd(dir / "block_drop.pvd");
  const std::string collection((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  EXPECT_NE(collection.find("timestep=\"0.1\""), std::string::npos);
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName((dir / "block_drop_0040.vtu").string().c_str());
  reader->Update();
  EXPECT_GT(reader->GetOutput()->GetNumberOfCells(), 0);
  fs::remove_all(dir);
}

// A probe pressing 0.3 N into the block of the shipped scene: the table takes 0.3 N, the probe's

// A symmetry plane: the left half of a block (Q1 hexahedra, the same cells as the full block's left
// half) with `type: symmetry` on its cut x = 0.05 reproduces the full block's answer, under its own
// weight and a traction over a band symmetric about the cut. Independent answer: the full model.
// Tolerance: both solve Newton to 1e-10 relative on identical cells, so they agree to round-off
// amplified by the conditioning, far below 1e-6 of the displacement.
TEST(SolveCommand, SymmetryPlaneHalfReproducesTheFullBlock) {
  const fs::path dir = scratch("symmetry");
  fs::create_directories(dir);
  const auto scene = [&](const std::string& name, double length, const std::string& extra) {
    const fs::path path = dir / (name + ".yaml");
    std::ofstream(path) << "name: " << name << "\nunits: SI\nmesh:\n"
                        << "  generate: {shape: box, size_m: [" << length << ", 0.08, 0.05], refinements: 2}\n"
                        << "  element: q1\n"
                        << "material: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.4, "
                           "density_kg_per_m3: 1050}\n"
                        << "effects:\n  - gravity\n"
                        << "solver: {newton: {relative_tolerance: 1.0e-10}}\n"
                        << "boundary:\n"
                        << "  - {name: base, type: fixed, select: {physical_group: zmin}}\n"
                        << "  - {name: press, type: traction, traction_pa: [0, 0, -400], "
                           "select: {box: {min: [0.03, -1, 0.0499], max: [0.07, 1, 1]}}}\n"
                        << extra;
    return path;
  };
  const fs::path full = scene("full", 0.1, "");
  const fs::path half = scene("half", 0.05,
                              "  - {name: cut, type: symmetry, select: {plane: {point: [0.05, 0, 0], normal: [1, 0, 0]}}}\n");
  const std::string points = " --point 0.04 0.04 0.05 --point 0.05 0.04 0.05 --point 0.02 0.01 0.025 --point 0.05 0.07 0.03";
  const auto solve = [&](const fs::path& path, const std::string& name) {
    const auto r = run_command(fetouch("solve --json --out " + (dir / name).string() + points + " " + path.string()));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return YAML::Load(r.out);
  };
  const YAML::Node a = solve(full, "full_out"), b = solve(half, "half_out");
  ASSERT_TRUE(a["converged"].as<bool>());
  ASSERT_TRUE(b["converged"].as<bool>());
  double largest = 0;
  for (std::size_t p = 0; p < 4; ++p)
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(a["points"][p]["displacement_m"][c].as<double>()));
  ASSERT_GT(largest, 1e-3);  // a real deformation: over a millimetre
  for (std::size_t p = 0; p < 4; ++p)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(b["points"][p]["displacement_m"][c].as<double>(), a["points"][p]["displacement_m"][c].as<double>(),
                  1e-6 * largest)
          << "point " << p << ", component " << c;
  // On the cut the full model moves along the plane only, as the half model's support imposes.
  EXPECT_LT(std::abs(a["points"][1]["displacement_m"][0].as<double>()), 1e-9);
  // The half carries half the weight and half the press: its base reaction is half the full one's.
  EXPECT_NEAR(b["reactions_n"]["base"][2].as<double>(), a["reactions_n"]["base"][2].as<double>() / 2,
              1e-6 * std::abs(a["reactions_n"]["base"][2].as<double>()));
  fs::remove_all(dir);
}

// patch moves down, and the VTU holds the displacement ParaView warps by, with J > 0 everywhere.
TEST(SolveCommand, PressWritesAVtuThatVtkReadsBack) {
  const fs::path dir = scratch("press");
  const auto r = run_command(fetouch("solve --json --out " + dir.string() + " " + FETOUCH_SOURCE_DIR +
                                     "/config/scenes/block_press.yaml --press 0.05 0.04 0.05 0 0 -0.3 --point 0.05 0.04 0"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  EXPECT_NEAR(j["reactions_n"]["table"][2].as<double>(), 0.3, 1e-7);
  EXPECT_LT(j["probes"][0]["displacement_m"][2].as<double>(), -1e-3);
  // A point on the fixed base does not move.
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(j["points"][0]["displacement_m"][d].as<double>(), 0, 1e-12);

  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName((dir / "block_press.vtu").c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  ASSERT_GT(grid->GetNumberOfPoints(), 0);
  vtkDataArray* u = grid->GetPointData()->GetArray("displacement");
  ASSERT_NE(u, nullptr);
  ASSERT_EQ(u->GetNumberOfComponents(), 3);
  double largest = 0;
  for (vtkIdType p = 0; p < u->GetNumberOfTuples(); ++p) {
    const double* v = u->GetTuple3(p);
    largest = std::max(largest, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  }
  EXPECT_NEAR(largest, j["max_displacement_m"].as<double>(), 1e-9);
  // deal.II writes per-cell values on its patches' points (constant over each cell).
  vtkDataArray* jacobian = grid->GetPointData()->GetArray("J");
  ASSERT_NE(jacobian, nullptr);
  double range[2];
  jacobian->GetRange(range);
  EXPECT_GT(range[0], 0.5);
  EXPECT_LT(range[1], 1.5);
  EXPECT_TRUE(fs::exists(dir / "block_press.pvd"));
  fs::remove_all(dir);
}

TEST(SolveCommand, BadInputIsRefusedWithAReason) {
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const auto off = run_command(fetouch("solve --out /tmp/fetouch_off " + scene + " --press 0.5 0.5 0.5 0 0 -1"));
  EXPECT_EQ(off.exit_code, 2);
  EXPECT_NE(off.err.find("no boundary surface within the radius"), std::string::npos) << off.err;
  EXPECT_EQ(run_command(fetouch("solve /no/such/scene.yaml")).exit_code, 2);
  EXPECT_EQ(run_command(fetouch("solve " + scene + " --press 0.05 0.04")).exit_code, 2);
  fs::remove_all("/tmp/fetouch_off");
}

}  // namespace
}  // namespace fetouch::testing
