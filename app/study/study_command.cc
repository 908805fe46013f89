// `fetouch study accuracy|effects|hard-cases|passivity` on the command line (app/study/study.h, docs/study.md).
#include <CLI/CLI.hpp>
#include <mpi.h>

#include <iostream>
#include <memory>
#include <stdexcept>

#include "app/cli.h"
#include "app/commands/commands.h"
#include "app/error_text.h"
#include "app/exit_codes.h"
#include "app/mpi_session.h"
#include "app/study/study.h"

namespace fetouch::app {

namespace {

void add_common(CLI::App* cmd, StudyOptions& o, const char* out) {
  o.out = out;
  cmd->add_option("--out", o.out, "Output folder (table.csv, report.md, study.json, plots)")->capture_default_str();
  cmd->add_flag("--json", o.json, "Print the study's summary as JSON on stdout (also written to OUT/study.json)");
  cmd->add_option("--threads", o.threads, "Assembly threads per solve (1 or 2), as in `fetouch replay`")
      ->check(CLI::Range(1, 2))->capture_default_str();
}

// Studies time one process: under mpirun they refuse rather than time a collective they do not run.
// Exceptions become one line: bad input (2) or the work failed (1).
int guarded(const StudyOptions& o, const std::function<int()>& work) {
  ensure_mpi();
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (ranks > 1) {
    std::cerr << "error: fetouch study times one process; run it without mpirun (MPI scaling: "
                 "`mpirun -n K fetouch replay SCENE`, docs/benchmarks.md)\n";
    return kExitBadInput;
  }
  try {
    return work();
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "error: " << naming(o.scene, e.what()) << "\n";
    return kExitFailure;
  }
}

}  // namespace

void add_study_command(CLI::App& parent, int& exit_code) {
  CLI::App* study = parent.add_subcommand("study", drawing_command_description("study"));
  study->require_subcommand(1);
  study->footer("Each study writes a table (CSV), a report (Markdown) and plots (PNG, drawn with VTK: run under\n"
                "`xvfb-run -a` without a display). docs/study.md tells what each measures.");

  auto a = std::make_shared<AccuracyOptions>();
  CLI::App* accuracy = study->add_subcommand("accuracy", "The accuracy-time trade-off of a scene's session");
  accuracy->footer(
      "Replays the scene's trajectory in lockstep with one knob turned at a time from the scene as it\n"
      "is: element size, element order, Newton tolerance, solver rate N, local model and hold; and\n"
      "compares each run's force, tick by tick, with a reference: the finest mesh of the sweep, Newton\n"
      "to 1e-10 (accuracy policy off), the solver at the haptic rate (N = 1). Writes OUT/table.csv,\n"
      "OUT/report.md (the Pareto set marked, the convergence order fitted) and two plots.");
  accuracy->add_option("scene", a->scene, "Scene file (.yaml)")->required()->check(CLI::ExistingFile);
  add_common(accuracy, *a, "fetouch-study-accuracy");
  accuracy->add_option("--mesh-levels", a->mesh_levels,
                       "Mesh levels: refinements added to a generated mesh, or the element size divided by 1.5^LEVEL\n"
                       "for a meshed volume (a mesh file has level 0 only)")
      ->delimiter(',')->check(CLI::Range(-4, 3))->capture_default_str();
  accuracy->add_option("--orders", a->orders, "Element orders (1, 2); default 1,2")->delimiter(',')->check(CLI::Range(1, 2));
  accuracy->add_option("--tolerances", a->tolerances, "Newton relative tolerances (accuracy policy off)")
      ->delimiter(',')->check(CLI::Range(1e-14, 0.5))->capture_default_str();
  accuracy->add_option("--ratios", a->ratios, "Haptic ticks per solver frame N")
      ->delimiter(',')->check(CLI::Range(2, 1000))->capture_default_str();
  accuracy->add_option("--models", a->models, "Local models and holds, MODEL/HOLD (p, pi, smith, pi_smith; zoh, foh); default all")
      ->delimiter(',');
  accuracy->add_option("--duration", a->duration_s, "Seconds of the trajectory to replay (0: all)")
      ->check(CLI::Range(0.0, 3600.0))->capture_default_str();
  accuracy->add_flag("--quick", a->quick,
                     "A small sweep: mesh levels -1,0, the scene's order, tolerance 1e-4, N = 10 and 50, p/zoh and\n"
                     "pi_smith/foh, the trajectory's first second");
  accuracy->callback([a, &exit_code]() { exit_code = guarded(*a, [a]() { return run_study_accuracy(*a); }); });

  auto e = std::make_shared<EffectsOptions>();
  CLI::App* effects = study->add_subcommand("effects", "What each effect of a scene costs a frame");
  effects->footer(
      "Replays the scene in lockstep as it is (twice, for the noise) and with each listed effect removed\n"
      "in turn; reports each run's frame times and each term's own time per frame, compares each\n"
      "removal's saving with its term's time over the frames of equal work, and shows that an effect\n"
      "the scene does not list has no term and runs no code. Writes OUT/table.csv, OUT/frames.csv,\n"
      "OUT/report.md and OUT/effects.png (a bar chart).");
  effects->add_option("scene", e->scene, "Scene file (.yaml)")->required()->check(CLI::ExistingFile);
  add_common(effects, *e, "fetouch-study-effects");
  effects->add_option("--duration", e->duration_s, "Seconds of the trajectory to replay (0: all)")
      ->check(CLI::Range(0.0, 3600.0))->capture_default_str();
  effects->add_flag("--quick", e->quick, "The trajectory's first second");
  effects->add_option("--repeat", e->repeat, "Runs of each configuration; each frame's time is its fastest")
      ->check(CLI::Range(1, 20))->capture_default_str();
  effects->callback([e, &exit_code]() { exit_code = guarded(*e, [e]() { return run_study_effects(*e); }); });

  auto p = std::make_shared<PassivityOptions>();
  CLI::App* passivity = study->add_subcommand("passivity", "The loop with a hand in it: a box of hands and events, the layer off and on");
  passivity->footer(
      "Holds every probe with the virtual operator along its trajectory and sweeps the hand (mass, grip\n"
      "stiffness, damping) and what it does (none, release, grip, tremor8/10/12, impact, at the middle\n"
      "of the default hand's contact), each with the passivity layer off, on, and with plain\n"
      "Hannaford-Ryu. Judges each run by one criterion (ringing above ~90 Hz for 0.3 s without halving, or\n"
      "chatter at the clamp), and the nominal run (default hand, no event) by the controller's share\n"
      "of ticks and the felt stiffness on against off. Writes OUT/table.csv, OUT/report.md and plots.");
  passivity->add_option("scene", p->scene, "Scene file (.yaml)")->required()->check(CLI::ExistingFile);
  add_common(passivity, *p, "fetouch-study-passivity");
  passivity->add_option("--masses", p->masses, "Hand masses, kg")->delimiter(',')->capture_default_str();
  passivity->add_option("--stiffnesses", p->stiffnesses, "Grip stiffnesses, N/m")->delimiter(',')->capture_default_str();
  passivity->add_option("--dampings", p->dampings, "Grip dampings, N s/m")->delimiter(',')->capture_default_str();
  passivity->add_option("--events", p->events, "none, release, grip, tremor8, tremor10, tremor12, impact")->delimiter(',');
  passivity->add_option("--modes", p->modes, "off, on, hannaford_ryu")->delimiter(',');
  passivity->add_option("--hand", p->hand,
                        "one_mass (mass, spring, damper) or stylus (Fu & Cavusoglu's two stages: the masses are the hand's, "
                        "the stiffnesses and dampings the grip's)")
      ->check(CLI::IsMember({"one_mass", "stylus"}))
      ->capture_default_str();
  passivity->add_option("--duration", p->duration_s, "Seconds of the trajectory to replay (0: all)")
      ->check(CLI::Range(0.0, 3600.0))->capture_default_str();
  passivity->add_flag("--quick", p->quick, "A corner of the box: masses 0.02,0.57, stiffnesses 230,2000, dampings 0.5,8; events none, release, tremor10, impact");
  passivity->callback([p, &exit_code]() {
    if (p->quick) p->masses = {0.02, 0.57}, p->stiffnesses = {230, 2000}, p->dampings = {0.5, 8}, p->events = {"none", "release", "tremor10", "impact"};
    exit_code = guarded(*p, [p]() { return run_study_passivity(*p); });
  });

  auto h = std::make_shared<HardCasesOptions>();
  CLI::App* hard = study->add_subcommand("hard-cases", "The solver's hard cases on a scene's tissue (or a block)");
  hard->footer(
      "Runs the hard-case battery (docs/study.md) on the scene's tissue, or on a built-in 10 x 8 x 5 cm\n"
      "block when no scene is given: each case must converge or be cut cleanly (rolled back, with a\n"
      "reason), with no inverted element and nothing that is not finite. Exit 0 only when every case is\n"
      "sound; 1 otherwise. Writes OUT/table.csv and OUT/report.md.");
  hard->add_option("scene", h->scene, "Scene file (.yaml); none: the built-in block")->check(CLI::ExistingFile);
  add_common(hard, *h, "fetouch-study-hard-cases");
  hard->add_flag("--no-line-search", h->no_line_search, "Break the solver on purpose: Newton takes every full step");
  hard->add_option("--max-cuts", h->max_cuts, "Load-step cuts allowed per solve (default 8; 0 breaks the hard cases)")
      ->check(CLI::Range(0, 20));
  hard->add_option("--random", h->random,
                   "Instead: replay N valid scenes drawn from the schema (every enum value in turn, numbers at their\n"
                   "range's edges), each by `fetouch replay` in a process of its own, bounded in time; each must run\n"
                   "to its end or fail with exit 1 and a physical reason (OUT/scenes/NAME/scene.yaml to rerun one)")
      ->check(CLI::Range(1, 100000));
  hard->add_option("--seed", h->seed, "The draw's seed (with --random)")->capture_default_str();
  hard->callback([h, &exit_code]() {
    if (h->random > 0 && !h->scene.empty()) {
      std::cerr << "error: --random draws its own scenes: give no scene\n";
      exit_code = kExitBadInput;
      return;
    }
    exit_code = guarded(*h, [h]() { return h->random > 0 ? run_study_random(*h) : run_study_hard_cases(*h); });
  });
}

}  // namespace fetouch::app
