// `fetouch study`: tables and plots a researcher can put in a paper, from lockstep sessions of any
// scene (docs/study.md). accuracy: what accuracy costs in time; effects: what each effect of a scene
// costs; hard-cases: the solver's hard cases on the scene's tissue, each converged or cleanly cut.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/exit_codes.h"
#include "app/study/study_table.h"
#include "config/scene.h"

namespace fetouch::app {

struct AccuracyOptions : StudyOptions {
  std::vector<int> mesh_levels{-2, -1, 0, 1};  // refinements added (generated), or element size / 1.5^level
  std::vector<int> orders;                     // empty: 1 and 2 (the scene's own alone with --quick)
  std::vector<double> tolerances{1e-3, 1e-5, 1e-8};
  std::vector<int> ratios{10, 20, 50, 100};
  std::vector<std::string> models;             // MODEL/HOLD; empty: all eight
  double duration_s = 0;                       // of the trajectory; 0: all of it
};

struct AccuracyReference {
  std::string text;
  unsigned int dofs = 0;
  long cells = 0, frames = 0, ticks = 0;
  double wall_s = 0, frame_p99_ms = 0, self_check = 0;
  std::vector<std::string> not_run;  // configurations that could not run, and why
};

int run_study_accuracy(const AccuracyOptions& options);

struct EffectsOptions : StudyOptions {
  double duration_s = 0;  // of the trajectory; 0: all of it (--quick: 1 s)
  int repeat = 3;         // runs of each configuration: each frame's time is the fastest of its runs
};
int run_study_effects(const EffectsOptions& options);

struct HardCasesOptions : StudyOptions {
  // Deliberately broken solver settings, to show that the battery can fail: Newton without its
  // line search, and no load-step cuts.
  bool no_line_search = false;
  int max_cuts = -1;  // < 0: the battery's own (8)
  int random = 0;     // > 0: this many valid scenes drawn from the schema instead (random_study.cc)
  unsigned int seed = 1;
};
// Exit 0 only when every case is sound.
int run_study_hard_cases(const HardCasesOptions& options);
// --random N: exit 0 only when every drawn scene ran to its end or failed with a physical reason.
int run_study_random(const HardCasesOptions& options);

// `fetouch study passivity`: the hand in the loop, swept (app/study/passivity_study.cc). The box's
// defaults: masses and grip stiffnesses of Fu & Cavusoglu 2012's stylus grips (0.02-0.57 kg,
// 230-1,040 N/m) and the stiff grip (2,000 N/m); dampings from a barely damped grip (0.5 N s/m)
// to the default hand's 8 N s/m.
struct PassivityOptions : StudyOptions {
  std::vector<double> masses{0.02, 0.1, 0.2, 0.4, 0.57};
  std::vector<double> stiffnesses{230, 500, 1040, 2000};
  std::vector<double> dampings{0.5, 2, 5, 8};
  std::vector<std::string> events{"none", "release", "grip", "tremor8", "tremor10", "tremor12", "impact"};
  std::vector<std::string> modes{"off", "on", "hannaford_ryu"};
  double duration_s = 0;  // of the trajectory; 0: all of it
  // The hand model the box sweeps: one_mass (mass, spring, damper) or stylus (the masses are the
  // hand's, the stiffnesses and dampings the grip's; the handle and the arm at their defaults).
  std::string hand = "one_mass";
};
int run_study_passivity(const PassivityOptions& options);

// Refuses an --out that would replace the scene, its mesh or a trajectory; creates the folder.
// Throws std::invalid_argument naming both.
void prepare_study_folder(const std::filesystem::path& out, const std::string& scene_file, const config::Scene& scene);

// STUDY/table.csv, STUDY/report.md, the plots, and the summary on stdout (JSON with --json).
int write_accuracy_outputs(const AccuracyOptions& options, const config::Scene& scene, const StudyTable& table,
                           const AccuracyReference& reference);

}  // namespace fetouch::app
