// `fetouch study`, the real binary: its tables read back and checked against recomputations that do
// not use the study's own code (the Pareto set by brute force, the convergence order from two
// points), and its hard-case battery shown able to fail. docs/study.md.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <vector>

#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
  double number(std::size_t row, const std::string& name) const {
    const std::string& cell = rows[row][column(name)];
    return cell.empty() ? std::nan("") : std::stod(cell);
  }
  const std::string& text(std::size_t row, const std::string& name) const { return rows[row][column(name)]; }
};

Table read_table(const fs::path& file) {
  Table t;
  std::istringstream in(read_file_text(file));
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
      cells.push_back(line.substr(start, comma - start));
    cells.push_back(line.substr(start));
    if (first) t.header = cells, first = false;
    else t.rows.push_back(cells);
  }
  return t;
}

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

// block_press.yaml one refinement coarser with a 15 mm probe: three mesh levels in a test's time.
const std::string kBlock = std::string(FETOUCH_SOURCE_DIR) + "/tests/data/block_study.yaml";

TEST(StudyAccuracy, ParetoSetIsItsTablesNonDominatedRowsAndTheErrorFallsUnderRefinement) {
  const fs::path out = fresh("study_accuracy");
  const CommandResult r = run_command(fetouch("-q study accuracy " + kBlock + " --mesh-levels 0,1,2 --orders 1 --tolerances 1e-4 "
                                              "--ratios 10 --models p/zoh,pi_smith/foh --duration 1.2 --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = read_table(out / "table.csv");
  ASSERT_GE(t.rows.size(), 5u);
  // The Pareto set, by brute force over the CSV's own frame times and errors.
  int marked = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    bool dominated = false;
    for (std::size_t j = 0; j < t.rows.size(); ++j) {
      const double ci = t.number(i, "frame_p99_ms"), ei = t.number(i, "force_rms_rel");
      const double cj = t.number(j, "frame_p99_ms"), ej = t.number(j, "force_rms_rel");
      if (cj <= ci && ej <= ei && (cj < ci || ej < ei)) dominated = true;
    }
    EXPECT_EQ(t.text(i, "pareto"), dominated ? "0" : "1") << "row " << i;
    marked += !dominated;
  }
  const std::string report = read_file_text(out / "report.md");
  int yes = 0;
  for (std::size_t at = 0; (at = report.find("| **yes** |", at)) != std::string::npos; ++at) ++yes;
  EXPECT_EQ(yes, marked);
  // The self-consistency check: the reference against itself.
  std::smatch m;
  const std::string json = read_file_text(out / "study.json");
  ASSERT_TRUE(std::regex_search(json, m, std::regex("\"self_check_rms_rel\": ?([-0-9.e+]+)")));
  EXPECT_LT(std::stod(m[1]), 1e-6);
  // Under refinement (levels 0, 1 against the reference on level 2, each level's own ideal at N = 1)
  // the discretisation's error falls, and the order the report fits is the one its two points give.
  std::map<std::string, std::size_t> level;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    if (t.text(i, "axis") == "baseline" || t.text(i, "axis") == "mesh") level[t.text(i, "mesh_level")] = i;
  ASSERT_EQ(level.size(), 3u);
  const std::size_t coarse = level.at("0"), fine = level.at("1");
  const double e0 = t.number(coarse, "discretisation_rel"), e1 = t.number(fine, "discretisation_rel");
  EXPECT_LT(e1, 0.5 * e0);
  EXPECT_EQ(t.number(level.at("2"), "discretisation_rel"), 0);  // the reference's own level
  EXPECT_LT(t.number(level.at("2"), "force_rms_rel"), t.number(coarse, "force_rms_rel"));
  const double slope = std::log(e1 / e0) / std::log(t.number(fine, "dofs") / t.number(coarse, "dofs"));
  ASSERT_TRUE(std::regex_search(report, m, std::regex("that is order \\*\\*([-0-9.]+)\\*\\*")));
  EXPECT_NEAR(std::stod(m[1]), -3 * slope, 0.01);
  EXPECT_NE(r.out.find("force error under refinement"), std::string::npos) << r.out;
  for (const char* png : {"error_vs_frame_time.png", "error_vs_dofs.png"}) EXPECT_GT(fs::file_size(out / png), 8000u) << png;
  fs::remove_all(out);
}

TEST(StudyEffects, EachEffectRemovedInTurnAndUnlistedGravityRunsNoCode) {
  const fs::path out = fresh("study_effects");
  const CommandResult r = run_command(fetouch("-q study effects " + std::string(FETOUCH_SOURCE_DIR) +
                                              "/tests/data/block_effects.yaml --duration 1 --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = read_table(out / "table.csv");
  std::map<std::string, std::size_t> run;
  for (std::size_t i = 0; i < t.rows.size(); ++i) run[t.text(i, "run")] = i;
  for (const char* name : {"as is", "as is (again)", "without gravity", "without inertia (and damping)", "without damping"})
    ASSERT_TRUE(run.count(name)) << name;
  // Gravity's code runs when the scene lists it, never when it does not; its term (the loads) then
  // takes no time because it is not built.
  EXPECT_GT(t.number(run.at("as is"), "gravity_evaluations"), 0);
  EXPECT_EQ(t.number(run.at("without gravity"), "gravity_evaluations"), 0);
  EXPECT_GT(t.number(run.at("as is"), "assembly_ms_loads"), 0);
  EXPECT_EQ(t.number(run.at("without gravity"), "assembly_ms_loads"), 0);
  EXPECT_GT(t.number(run.at("as is"), "assembly_ms_inertia"), 0);
  EXPECT_EQ(t.number(run.at("without inertia (and damping)"), "assembly_ms_inertia"), 0);
  EXPECT_EQ(t.number(run.at("without inertia (and damping)"), "assembly_ms_damping"), 0);
  EXPECT_EQ(t.number(run.at("without damping"), "assembly_ms_damping"), 0);
  EXPECT_GT(fs::file_size(out / "effects.png"), 8000u);

  // Each removal at equal work, recomputed from the per-frame table: the frames in which the run
  // without the effect did the work the scene as is did, but the removed terms' own.
  EXPECT_EQ(t.text(run.at("without gravity"), "removed_terms"), "loads");
  EXPECT_EQ(t.text(run.at("without inertia (and damping)"), "removed_terms"), "inertia damping");
  EXPECT_EQ(t.text(run.at("without damping"), "removed_terms"), "damping");
  const Table f = read_table(out / "frames.csv");
  std::map<std::string, std::vector<std::size_t>> frames;  // run -> its rows, in frame order
  for (std::size_t i = 0; i < f.rows.size(); ++i) frames[f.text(i, "run")].push_back(i);
  const auto zero = [&f](std::size_t i, const char* column) { return f.number(i, column) == 0; };
  for (const auto& [name, terms] : std::map<std::string, std::vector<std::string>>{
           {"without gravity", {"loads"}}, {"without inertia (and damping)", {"inertia", "damping"}}, {"without damping", {"damping"}}}) {
    const std::vector<std::size_t>&a = frames.at("as is"), &b = frames.at(name);
    ASSERT_EQ(a.size(), b.size());
    int matched = 0;
    double saved = 0, own = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      const std::size_t i = a[k], j = b[k];
      double own_ms = 0, own_linear = 0;
      for (const std::string& term : terms) own_ms += f.number(i, "own_ms_" + term), own_linear += f.number(i, "own_linear_" + term);
      const bool same = f.number(i, "converged") == 1 && f.number(j, "converged") == 1 &&
                        f.number(i, "newton") == f.number(j, "newton") && f.number(i, "cuts") == f.number(j, "cuts") &&
                        f.number(i, "linear") - own_linear == f.number(j, "linear") && zero(i, "factorisations") &&
                        zero(j, "factorisations") && zero(i, "factorisation_ms") && zero(j, "factorisation_ms") &&
                        zero(i, "background") && zero(j, "background") &&
                        f.number(i, "compliance_linear") == f.number(j, "compliance_linear") &&
                        zero(i, "compliance_factorisations") && zero(j, "compliance_factorisations") &&
                        f.number(i, "compliance_refined") == f.number(j, "compliance_refined");
      if (!same) continue;
      ++matched;
      saved += f.number(i, "solve_ms") - f.number(j, "solve_ms");
      own += own_ms;
    }
    const std::size_t row = run.at(name);
    EXPECT_GT(matched, 3) << name;
    EXPECT_EQ(matched, t.number(row, "equal_work_frames")) << name;
    EXPECT_NEAR(saved / matched, t.number(row, "equal_work_saved_ms"), 1e-9) << name;
    EXPECT_NEAR(own / matched, t.number(row, "equal_work_own_ms"), 1e-9) << name;
    EXPECT_EQ(t.text(row, "equal_work_holds"),
              std::abs(saved - own) / matched <= t.number(row, "equal_work_tolerance_ms") ? "1" : "0") << name;
  }
  fs::remove_all(out);
}

TEST(StudyHardCases, SoundOnTheBlockAndNotSoundWhenTheSolverIsBroken) {
  const fs::path out = fresh("study_hard");
  CommandResult r = run_command(fetouch("-q study hard-cases --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  Table t = read_table(out / "table.csv");
  EXPECT_EQ(t.rows.size(), 11u);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    EXPECT_EQ(t.text(i, "sound"), "1") << t.text(i, "case");
    EXPECT_EQ(t.text(i, "finite"), "1") << t.text(i, "case");
    EXPECT_GT(t.number(i, "min_j"), 0) << t.text(i, "case");
  }
  // No load-step cuts: the 40 % compression in one step inverts an element, and the battery says so.
  r = run_command(fetouch("-q study hard-cases --max-cuts 0 --out " + out.string()));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  t = read_table(out / "table.csv");
  EXPECT_EQ(t.text(0, "case"), "40 % compression");
  EXPECT_EQ(t.text(0, "sound"), "0");
  EXPECT_NE(read_file_text(out / "report.md").find("Not every case is sound"), std::string::npos);
  r = run_command(fetouch("-q study hard-cases --no-line-search --out " + out.string()));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  fs::remove_all(out);
}

// The hand in the loop (issue 39): the shipped hard case (a 20 g, 2,000 N/m, 0.5 N s/m grip on a
// 1 MPa block) rings with the layer off, as the replay test shows from the recording itself
// (test_passivity_replay.cc), and the study must say so; with the layer on it rings far less and
// never at the clamp, and plain Hannaford-Ryu is run beside it. The judge itself is tested on known signals
// (test_passivity_metrics.cc).
TEST(StudyPassivity, TheHardCaseRingsWithTheLayerOffAndFarLessWithItOn) {
  const fs::path out = fresh("study_passivity");
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/stiff_block_grip.yaml";
  CommandResult r = run_command(fetouch("-q study passivity " + scene + " --masses 0.02 --stiffnesses 2000 --dampings 0.5 "
                                        "--events none,impact --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const Table t = read_table(out / "table.csv");
  ASSERT_EQ(t.rows.size(), 9u);  // per mode: the nominal run, then the hand with each event
  int nominal = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::string mode = t.text(i, "mode"), what = mode + " " + t.text(i, "event");
    if (t.text(i, "nominal") == "1") {
      ++nominal;
      EXPECT_EQ(t.number(i, "mass_kg"), 0.3);  // config::HandModel's default hand
      // The lifting with the hand in the loop calls the default hand unstable on the 1 MPa block
      // (radius 1.31 at the gains proven without it), and the run itself rings with the layer off.
      if (mode == "off") {
        EXPECT_GT(t.number(i, "lifted_radius_with_hand"), 1) << what;
        EXPECT_EQ(t.text(i, "oscillates"), "1") << what;
      }
      continue;
    }
    EXPECT_TRUE(t.text(i, "error").empty()) << what << ": " << t.text(i, "error");
    EXPECT_LE(t.number(i, "max_force_n"), 8.5 * (1 + 1e-9)) << what;
    if (mode == "off") {
      EXPECT_EQ(t.number(i, "controller_ticks"), 0) << what;
      if (t.text(i, "event") == "none") {
        EXPECT_EQ(t.text(i, "oscillates"), "1") << what;
        EXPECT_GT(t.number(i, "lifted_radius_with_hand"), 1) << what;  // and the lifting with that hand says so
      }
    } else if (mode == "on") {
      // The layer acts on energy already handed over: the first contact still rings while s halves
      // (measured 0.3 s, 0.62 N), but never at the clamp, and far less than without it (2.5 s, 4.6 N).
      EXPECT_EQ(t.number(i, "chatter_ticks"), 0) << what;
      EXPECT_LE(t.number(i, "ringing_s"), 0.5) << what;
      EXPECT_LT(t.number(i, "min_scale"), 1) << what;
      EXPECT_LT(t.number(i, "adjusting_ticks"), t.number(i, "controller_ticks")) << what;
    } else {
      EXPECT_EQ(mode, "hannaford_ryu");
      EXPECT_GT(t.number(i, "adjusting_ticks"), 0) << what;
    }
  }
  EXPECT_EQ(nominal, 3);
  // Every run is set against the same hand on the ideal tissue (passivity_metrics.h; the ideal wall is
  // checked against closed forms in test_passivity_metrics.cc): each mode sees the same ideal.
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    for (std::size_t j = 0; j < t.rows.size(); ++j)
      if (t.text(i, "event") == t.text(j, "event") && t.text(i, "nominal") == t.text(j, "nominal")) {
        EXPECT_EQ(t.number(i, "ideal_bounces"), t.number(j, "ideal_bounces")) << t.text(i, "event");
      }
  // Without the layer the same hand and events ring longer and harder.
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    for (std::size_t j = 0; j < t.rows.size(); ++j)
      if (t.text(i, "mode") == "off" && t.text(j, "mode") == "on" && t.text(i, "nominal") == "0" && t.text(j, "nominal") == "0" &&
          t.text(i, "event") == t.text(j, "event")) {
        EXPECT_GT(t.number(i, "ringing_s"), 3 * t.number(j, "ringing_s")) << t.text(i, "event");
        EXPECT_GT(t.number(i, "ringing_ptp_n"), 4 * t.number(j, "ringing_ptp_n")) << t.text(i, "event");
      }
  const std::string report = read_file_text(out / "report.md");
  EXPECT_NE(report.find("## Verdicts"), std::string::npos);
  EXPECT_NE(read_file_text(out / "study.json").find("\"oscillating\""), std::string::npos);
  // An unknown mode is bad input, named.
  r = run_command(fetouch("-q study passivity " + scene + " --modes off,bogus --out " + out.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bogus"), std::string::npos) << r.err;
  r = run_command(fetouch("-q study passivity " + scene + " --hand glove --out " + out.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("glove"), std::string::npos) << r.err;
  // The stylus grip: the nominal run is the default stylus (0.21 kg, 575 N/m, 1.3 N s/m), the box's
  // hands are its grip stages, and the report says so.
  r = run_command(fetouch("-q study passivity " + scene + " --hand stylus --masses 0.02 --stiffnesses 1040 --dampings 0.5 "
                          "--events none --modes off --duration 1.2 --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const Table stylus = read_table(out / "table.csv");
  ASSERT_EQ(stylus.rows.size(), 2u);
  EXPECT_EQ(stylus.number(0, "mass_kg"), 0.21);
  EXPECT_EQ(stylus.number(0, "stiffness_n_per_m"), 575);
  EXPECT_NE(read_file_text(out / "report.md").find("two-stage stylus"), std::string::npos);
  fs::remove_all(out);
}

// The default scene's tissue: the anatomy, its liquid-filled sac kept at volume. Before the solver
// dropped a failed factorisation (fem/tangent_system.cc) four cases failed here at 1/256 of their
// load, and before a jumping patch slid there in steps (fem/fem_environment.cc) the teleport did.
TEST(StudyHardCases, SoundOnTheDefaultScene) {
  const fs::path out = fresh("study_hard_default");
  const CommandResult r = run_command(fetouch("-q study hard-cases " + std::string(FETOUCH_SOURCE_DIR) +
                                              "/config/scenes/fetus_phantom.yaml --out " + out.string()));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const Table t = read_table(out / "table.csv");
  EXPECT_EQ(t.rows.size(), 11u);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    EXPECT_EQ(t.text(i, "sound"), "1") << t.text(i, "case");
    EXPECT_EQ(t.text(i, "finite"), "1") << t.text(i, "case");
  }
  fs::remove_all(out);
}

// Valid scenes drawn from the schema (app/study/random_scenes.h), each replayed by the real binary:
// every one runs to its end or fails with exit 1 and a physical reason (issue 41). Checked here from
// what each replay wrote, not from the study's verdicts: its summary's forces against the clamp its
// scene file states, its unstable frames, its standard error.
TEST(StudyHardCases, RandomValidScenesRunToTheirEndOrSayWhyNot) {
  const fs::path out = fresh("study_random");
  const CommandResult r = run_command(fetouch("-q study hard-cases --random 24 --seed 1 --out " + out.string()));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const Table t = read_table(out / "table.csv");
  ASSERT_EQ(t.rows.size(), 24u);
  const std::regex number_after(R"("max_force_n":\s*([-+0-9.eE]+|null))"), unstable(R"("frames_with_unstable_gains":\s*([0-9]+))"),
      clamp(R"(max_force_n: ([-+0-9.eE]+))");
  int ran = 0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const std::string name = t.text(i, "scene");
    const fs::path dir = out / "scenes" / name;
    const std::string exit = t.text(i, "exit");
    ASSERT_TRUE(exit == "0" || exit == "1") << name << ": exit " << exit << ": " << t.text(i, "reason");
    if (exit == "1") {
      EXPECT_NE(read_file_text(dir / "stderr.txt").find("error: the work failed"), std::string::npos) << name;
      continue;
    }
    ++ran;
    const std::string summary = read_file_text(dir / "run" / "summary.json"), scene = read_file_text(dir / "scene.yaml");
    std::smatch force, frames, limit;
    ASSERT_TRUE(std::regex_search(summary, force, number_after)) << name;
    ASSERT_TRUE(std::regex_search(summary, frames, unstable)) << name;
    ASSERT_TRUE(std::regex_search(scene, limit, clamp)) << name;
    const double f = force[1] == "null" ? std::nan("") : std::stod(force[1]);
    EXPECT_TRUE(std::isfinite(f)) << name;
    EXPECT_LE(f, std::stod(limit[1]) * (1 + 1e-9)) << name;
    EXPECT_EQ(frames[1], "0") << name;
  }
  EXPECT_GE(ran, 22) << "at least 90 % of the drawn scenes run to their end (97 % is the goal over 200)";
  fs::remove_all(out);
}

}  // namespace
}  // namespace fetouch::testing
