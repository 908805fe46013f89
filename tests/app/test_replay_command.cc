// `fetouch replay`, the real binary on the shipped block scene in lockstep: the recording reopens
// with every tick; two runs give the same force series bit for bit; forces stay finite and under
// the scene's maximum; and at the end of the poke's hold the rendered force is the one the FEM
// equilibrium needs for that indentation (`fetouch solve` with that force moves the surface by the
// depth the probe holds, a second, independent route through the solver).
#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <iterator>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "app/recording.h"
#include "haptics/devices.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"
#include "tests/support/vtk_fields.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

double largest_displacement(const fs::path& vtu) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(vtu.string().c_str());
  reader->Update();
  return largest_point_vector(reader->GetOutput());
}

TEST(ReplayCommand, BlockPokeIsReproducibleAndMatchesTheStaticSolve) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  std::vector<app::Recording> runs;
  for (const char* name : {"a", "b"}) {
    const auto r = run_command(fetouch("replay --json --out " + (dir / name).string() + " " + scene));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const YAML::Node j = YAML::Load(r.out);
    EXPECT_EQ(j["ticks"].as<long>(), 3001);  // 3 s at 1 kHz, both ends
    EXPECT_EQ(j["frames"].as<long>(), 60);
    EXPECT_EQ(j["newton_failures"].as<long>(), 0);
    EXPECT_GT(j["min_stability_margin"].as<double>(), 0);
    EXPECT_LE(j["max_force_n"].as<double>(), 3.3);
    runs.push_back(app::read_recording(dir / name / "recording.h5"));
  }
  const auto& a = runs[0].devices.at(0).samples;
  const auto& b = runs[1].devices.at(0).samples;
  ASSERT_EQ(a.size(), 3001u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(std::memcmp(a[k].force.data(), b[k].force.data(), 3 * sizeof(double)), 0) << "tick " << k;
    ASSERT_TRUE(a[k].force.allFinite());
  }
  EXPECT_NE(runs[0].header.scene_text.find("block_press"), std::string::npos);

  // End of the hold (t = 2 s): the probe 8 mm below the top face; the force rendered then, applied
  // statically at the same place, must move the surface by about as much (the PI model drives the
  // penetration to zero; the patch spreads the load over the probe's radius).
  const auto& held = a[2000];
  ASSERT_TRUE(held.in_contact);
  // The force on the tissue as the loop handed it over: the local model's normal force along the
  // held normal (the device's force is the same direction, after the safety layer).
  const double force = held.normal_force;
  ASSERT_GT(force, 0.3);
  const Eigen::Vector3d on_tissue = -force * held.force.normalized();
  char press[160];
  std::snprintf(press, sizeof press, " --press 0.05 0.04 0.05 %.17g %.17g %.17g", on_tissue.x(), on_tissue.y(), on_tissue.z());
  const auto s = run_command(fetouch("solve --json --out " + (dir / "static").string() + " " + scene + press));
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const YAML::Node j = YAML::Load(s.out);
  const double sag = -j["probes"][0]["displacement_m"][2].as<double>();
  std::printf("held force %.4f N; static solve with it: the patch moves %.3f mm (the probe holds 8 mm)\n", force, 1e3 * sag);
  EXPECT_NEAR(sag, 0.008, 0.0008);

  // The deformed meshes, as ParaView opens them. The one at t = 2 s is the tissue's answer to the
  // samples of tick 2000, i.e. to the force above: reached frame by frame from the previous state,
  // it must be the static solve's state (hyperelastic equilibrium does not depend on the path),
  // read back by VTK from both files, to the accuracy a frame promises: the scene's default policy
  // (accuracy.position_m 1e-5 m at the contact, whose point moves most; a held frame stops at the
  // linear prediction once that holds, not at Newton's relative tolerance). The one at rest is
  // undeformed.
  const std::string pvd = read_file_text(dir / "a" / "block_press.pvd");
  ASSERT_NE(pvd.find("mesh/block_press_40.vtu"), std::string::npos) << pvd;
  const double replayed = largest_displacement(dir / "a" / "mesh" / "block_press_40.vtu");
  const double solved = largest_displacement(dir / "static" / "block_press.vtu");
  std::printf("largest displacement: replay frame 40 %.4f mm, static solve %.4f mm\n", 1e3 * replayed, 1e3 * solved);
  EXPECT_NEAR(replayed, solved, 1e-5);
  EXPECT_EQ(largest_displacement(dir / "a" / "mesh" / "block_press_0.vtu"), 0);
  fs::remove_all(dir);
}

// The shipped fetal scene: its tissue is the phantom, generated and meshed on first use (cached);
// a second run reuses the mesh and renders the same forces; the poke reaches contact, the force
// stays under the device maximum and the gains stay stable at every frame.
TEST(ReplayCommand, FetusPhantomSceneMeshesOnceAndReplays) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_fetus_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string env = "FETOUCH_CACHE_DIR=" + (dir / "cache").string() + " ";
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/fetus_simple.yaml";
  std::vector<app::Recording> runs;
  for (const char* name : {"a", "b"}) {
    const auto r = run_command(env + fetouch("replay --json --mesh-every 0 --out " + (dir / name).string() + " " + scene));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("meshing the scene's phantom") != std::string::npos, std::string(name) == "a") << r.err;
    const YAML::Node j = YAML::Load(r.out);
    EXPECT_EQ(j["newton_failures"].as<long>(), 0);
    EXPECT_GT(j["min_stability_margin"].as<double>(), 0);
    EXPECT_EQ(j["frames_with_unstable_gains"].as<long>(), 0);
    EXPECT_LE(j["max_force_n"].as<double>(), 3.3);
    runs.push_back(app::read_recording(dir / name / "recording.h5"));
  }
  const auto& a = runs[0].devices.at(0).samples;
  const auto& b = runs[1].devices.at(0).samples;
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k)
    ASSERT_EQ(std::memcmp(a[k].force.data(), b[k].force.data(), 3 * sizeof(double)), 0) << "tick " << k;
  EXPECT_TRUE(a[1600].in_contact);  // mid-hold
  EXPECT_GT(a[1600].normal_force, 0.2);
  EXPECT_FALSE(a[2990].in_contact);  // lifted off
  fs::remove_all(dir);
}

// The multirate local models against the ideal reference (the solver at the haptic rate) on the
// block's poke: eight local model / hold pairs reported; the best stays within 10 % RMS of the
// ideal force and settles to 2 % within 0.3 s of the hold's start (issue 6's figures).
TEST(ReplayCommand, CompareIdealReportsEveryPair) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_ideal_" + std::to_string(::getpid()));
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const auto r = run_command(fetouch("replay --json --compare-ideal --mesh-every 0 --out " + dir.string() + " " + scene));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node c = YAML::Load(r.out)["compare_ideal"];
  ASSERT_TRUE(c);
  EXPECT_EQ(c["hold_s"][0].as<double>(), 1.0);  // poke_block.csv holds from 1 s to 2 s
  ASSERT_EQ(c["pairs"].size(), 8u);
  double best = 1e9, best_settling = 1e9;
  for (const auto& pair : c["pairs"]) {
    const double rms = pair["rms_error_relative"][0].as<double>();
    std::printf("%-9s %s: RMS error %.2f %%, peak %.4f N, settling %.3f s\n", pair["local_model"].as<std::string>().c_str(),
                pair["hold"].as<std::string>().c_str(), 100 * rms, pair["peak_error_n"][0].as<double>(),
                pair["settling_s"][0].as<double>());
    EXPECT_GE(rms, 0);
    if (rms < best) best = rms, best_settling = pair["settling_s"][0].as<double>();
  }
  EXPECT_LT(best, 0.10);
  EXPECT_LE(best_settling, 0.3);
  fs::remove_all(dir);
}

// The shipped trajectories are the project's own: each file's "generated by:" line, run again,
// writes the same rows.
TEST(ReplayCommand, ShippedTrajectoriesAreRegeneratedByTheirCommand) {
  const fs::path folder = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "trajectories";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".csv") continue;
    const std::string text = read_file_text(entry.path());
    const auto at = text.find("# generated by: fetouch ");
    ASSERT_NE(at, std::string::npos) << entry.path() << " does not say how it was made";
    const auto start = at + std::string("# generated by: fetouch ").size();
    const std::string arguments = text.substr(start, text.find('\n', start) - start);
    const fs::path again = fs::temp_directory_path() / ("fetouch_regenerated_" + std::to_string(::getpid()) + ".csv");
    ASSERT_EQ(run_command(fetouch(arguments + " --out " + again.string())).exit_code, 0) << arguments;
    const haptics::Trajectory shipped = haptics::read_trajectory_csv(entry.path());
    const haptics::Trajectory made = haptics::read_trajectory_csv(again);
    EXPECT_EQ(made.times_s, shipped.times_s) << entry.path();
    ASSERT_EQ(made.positions_m.size(), shipped.positions_m.size());
    for (std::size_t i = 0; i < made.positions_m.size(); ++i) EXPECT_EQ(made.positions_m[i], shipped.positions_m[i]) << entry.path();
    fs::remove(again);
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

// The real-time clock against lockstep on the block poke. Real time takes an answer up when it
// arrives, and a background factorisation as soon as it is ready (lockstep: at a fixed frame), so
// the preconditioner, and with it the converged state, may differ within the accuracy policy: each
// answer's contact displacement is within 10 um of the exact one, two answers within 20 um of each
// other, 0.25 % of the 8 mm press; allowed: 1 % of the peak force (the tissue stiffens under the
// press) up to the first late answer (summary: first_late_tick; this scene solves in a few ms of its
// 50 ms frames, so normally there is none). After a late answer (a loaded machine) the tolerance is
// 10 % RMS of the force: a late answer is taken up one frame (50 ms) later, while the integrator
// pauses on the held surface; the press moves the probe 8 mm in 0.5 s, so one frame of lag is 0.8 mm
// of the 8 mm indentation, about 10 % of the force during the press, and nothing during the approach
// and the hold.
TEST(ReplayCommand, RealTimeRendersTheLockstepForces) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replay_rt_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const auto lock = run_command(fetouch("replay --json --mesh-every 0 --out " + (dir / "lockstep").string() + " " + scene));
  ASSERT_EQ(lock.exit_code, 0) << lock.err;
  const auto real = run_command(fetouch("replay --json --clock realtime --mesh-every 0 --out " + (dir / "realtime").string() + " " + scene));
  ASSERT_EQ(real.exit_code, 0) << real.err;
  const YAML::Node j = YAML::Load(real.out);
  EXPECT_EQ(j["clock"].as<std::string>(), "realtime");
  EXPECT_EQ(j["ticks"].as<long>(), 3001);
  EXPECT_EQ(j["dropped_samples"].as<long>(), 0);
  for (const char* key : {"p50", "p99", "max"}) {
    EXPECT_GT(j["tick_period_s"][key].as<double>(), 0) << key;
    EXPECT_GE(j["tick_lateness_s"][key].as<double>(), 0) << key;
  }
  const long late = j["overruns"].as<long>(), first_late = j["first_late_tick"].as<long>();
  std::printf("real time: tick period p50 %.4f ms, p99 %.4f ms, max %.4f ms; %ld late answers (first at tick %ld)\n",
              1e3 * j["tick_period_s"]["p50"].as<double>(), 1e3 * j["tick_period_s"]["p99"].as<double>(),
              1e3 * j["tick_period_s"]["max"].as<double>(), late, first_late);
  EXPECT_EQ(late == 0, first_late < 0);
  const auto a = app::read_recording(dir / "lockstep" / "recording.h5").devices.at(0).samples;
  const auto b = app::read_recording(dir / "realtime" / "recording.h5").devices.at(0).samples;
  ASSERT_EQ(a.size(), 3001u);
  ASSERT_EQ(b.size(), a.size());
  const std::size_t exact = first_late < 0 ? a.size() : static_cast<std::size_t>(first_late);
  double difference2 = 0, force2 = 0, early_peak = 0, peak_force = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (k < exact) early_peak = std::max(early_peak, (a[k].force - b[k].force).norm());
    peak_force = std::max(peak_force, a[k].force.norm());
    ASSERT_EQ(a[k].position, b[k].position) << k;  // the replay device plays the same points
    difference2 += (a[k].force - b[k].force).squaredNorm();
    force2 += a[k].force.squaredNorm();
  }
  EXPECT_GT(force2, 0);
  std::printf("before the first late answer: largest force difference %.3g N (%.3g of the peak)\n", early_peak, early_peak / peak_force);
  EXPECT_LE(early_peak, 0.01 * peak_force);
  EXPECT_LE(std::sqrt(difference2 / force2), 0.10);
  fs::remove_all(dir);
}

TEST(ReplayCommand, BadRequestsAreRefused) {
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  // An output folder of this run's own: a file left at a shared name (/tmp/x until 2026-12-03)
  // turned the trajectory's error below into one about --out.
  const fs::path out = fs::temp_directory_path() / ("fetouch_bad_out_" + std::to_string(::getpid()));
  const auto clock = run_command(fetouch("replay --clock wall --out " + out.string() + " " + scene));
  EXPECT_NE(clock.exit_code, 0);
  EXPECT_NE(clock.err.find("wall"), std::string::npos) << clock.err;
  const fs::path bad = fs::temp_directory_path() / ("fetouch_bad_traj_" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(bad) << "t,x,y,z\n0,0,0,0\n1,0,0\n"; }
  const auto broken = run_command(fetouch("replay --trajectory " + bad.string() + " --out " + out.string() + " " + scene));
  EXPECT_EQ(broken.exit_code, 2);
  EXPECT_NE(broken.err.find(bad.string() + ":3:"), std::string::npos) << broken.err;
  fs::remove(bad);
  fs::remove_all(out);
}

}  // namespace
}  // namespace fetouch::testing
