// `fetouch study hard-cases --random N --seed S`: N valid scenes drawn from the schema
// (random_scenes.h), each replayed by the real `fetouch replay` in a process of its own, bounded in
// time. Each must run to its end (exit 0: forces finite and within the clamp, no frame with unstable
// gains), or fail with exit 1 and a physical reason; a refusal at run time (exit 2), a crash or a
// replay that does not end is a defect, reported with its scene.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "app/json_writer.h"
#include "app/log.h"
#include "app/output_guard.h"
#include "app/progress.h"
#include "app/study/random_scenes.h"
#include "app/study/study.h"

extern char** environ;

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct Run {
  int exit_code = -1;  // -1: killed at its time limit
  double wall_s = 0;
};

// `program args...` with stdout and stderr to files, killed after `limit_s`.
Run run_bounded(const std::vector<std::string>& args, const fs::path& out, const fs::path& err, double limit_s) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(spawned));
  Run run;
  for (;;) {
    int status = 0;
    const pid_t done = waitpid(pid, &status, WNOHANG);
    run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (done == pid) {
      run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return run;
    }
    if (run.wall_s > limit_s) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      run.exit_code = -1;
      return run;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A number `"key": value` of a summary.json (NaN when absent or not a number).
double json_number(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\"" + key + "\":");
  if (at == std::string::npos) return std::nan("");
  const char* start = text.c_str() + at + key.size() + 3;
  char* end = nullptr;
  const double value = std::strtod(start, &end);
  return end == start ? std::nan("") : value;
}

// The first `error: ` line of a replay's standard error, without the prefix.
std::string error_line(const std::string& err) {
  std::istringstream lines(err);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("error: ", 0) == 0) return line.substr(7);
  return err.empty() ? std::string() : err.substr(0, err.find('\n'));
}

struct Outcome {
  RandomScene scene;
  fs::path file;
  Run run;
  double max_force_n = 0, clamp_n = 0, limit_s = 0;
  long unstable_frames = 0, newton_failures = 0, frames = 0;
  std::string verdict, reason;  // verdict: "ran", "failed", "DEFECT"
};

double clamp_of(const std::string& yaml) {
  const std::size_t at = yaml.find("max_force_n: ");
  return at == std::string::npos ? 3.3 : std::strtod(yaml.c_str() + at + 13, nullptr);
}

Outcome judge(Outcome o, const fs::path& run_dir) {
  const std::string err = read_text(run_dir / "stderr.txt");
  const std::string summary = read_text(run_dir / "summary.json");
  o.clamp_n = clamp_of(o.scene.yaml);
  if (o.run.exit_code == -1) {
    o.verdict = "DEFECT", o.reason = "did not end within " + format_number(o.limit_s) + " s";
  } else if (o.run.exit_code == 0) {
    o.max_force_n = json_number(summary, "max_force_n");
    const auto count = [&summary](const char* key) {  // -1 where the summary lacks it
      const double value = json_number(summary, key);
      return std::isfinite(value) ? static_cast<long>(value) : -1L;
    };
    o.unstable_frames = count("frames_with_unstable_gains");
    o.newton_failures = count("newton_failures");
    o.frames = count("frames");
    o.verdict = "ran";
    if (!(std::isfinite(o.max_force_n) && o.max_force_n <= o.clamp_n * (1 + 1e-9)))
      o.verdict = "DEFECT", o.reason = "a force of " + format_number(o.max_force_n) + " N against a clamp of " + format_number(o.clamp_n) + " N";
    else if (o.unstable_frames != 0 || o.frames < 0)
      o.verdict = "DEFECT", o.reason = o.frames < 0 ? "no readable summary.json"
                                                    : std::to_string(o.unstable_frames) + " frames with unstable gains";
  } else if (o.run.exit_code == 1 && err.find("error: the work failed") != std::string::npos) {
    o.verdict = "failed", o.reason = error_line(err);
  } else {
    o.verdict = "DEFECT";
    o.reason = (o.run.exit_code == 2 ? "refused at run time: " : "exit " + std::to_string(o.run.exit_code) + ": ") + error_line(err);
  }
  return o;
}

}  // namespace

int run_study_random(const HardCasesOptions& o) {
  const fs::path out(o.out);
  fs::create_directories(out / "scenes");
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find the fetouch binary to run the replays: " + error.message());
  log::info() << "replaying " << o.random << " scenes drawn with seed " << o.seed << ", each in a process of its own";
  Progress progress("study hard-cases --random", o.random, std::cerr, Progress::stderr_is_terminal());
  std::vector<Outcome> outcomes;
  for (int i = 0; i < o.random; ++i) {
    Outcome c;
    c.scene = random_scene(o.seed, i);
    const fs::path dir = out / "scenes" / c.scene.name;
    c.file = write_random_scene(c.scene, dir);
    // Bounded: P1 replays are expected within 10x their simulated time on one core (the report
    // counts those over it); a replay is stopped at 30x (100x for the others), at least 60 s.
    c.limit_s = std::max(60.0, (c.scene.p1 ? 30 : 100) * c.scene.duration_s);
    try {
      c.run = run_bounded({self.string(), "-q", "replay", c.file.string(), "--out", (dir / "run").string(), "--mesh-every", "0"},
                          dir / "stdout.txt", dir / "stderr.txt", c.limit_s);
    } catch (const std::exception& e) {  // the replay could not start: this scene's defect, the others still run
      c.run.exit_code = 127;
      std::ofstream(dir / "stderr.txt") << "error: " << e.what() << "\n";
    }
    fs::create_directories(dir / "run");
    fs::copy_file(dir / "stderr.txt", dir / "run" / "stderr.txt", fs::copy_options::overwrite_existing, error);
    c = judge(std::move(c), dir / "run");
    log::info() << c.scene.name << " (" << c.scene.summary << "): " << c.verdict << (c.reason.empty() ? "" : ": " + c.reason)
                << ", " << format_number(std::round(c.run.wall_s * 10) / 10) << " s";
    outcomes.push_back(std::move(c));
    progress.update(i + 1);
  }
  progress.finish();

  long ran = 0, failed = 0, defects = 0, slow = 0, p1 = 0;
  StudyTable table;
  table.columns = {"scene", "summary", "exit", "verdict", "reason", "wall_s", "simulated_s", "time_ratio", "max_force_n",
                   "clamp_n", "newton_failures", "unstable_frames"};
  const auto cell = [](std::string text) {
    for (char& ch : text) ch = ch == ',' ? ';' : ch == '\n' ? ' ' : ch;
    return text;
  };
  for (const Outcome& c : outcomes) {
    ran += c.verdict == "ran", failed += c.verdict == "failed", defects += c.verdict == "DEFECT";
    if (c.scene.p1) ++p1, slow += c.run.wall_s > 10 * c.scene.duration_s;
    table.rows.push_back({c.scene.name, cell(c.scene.summary), std::to_string(c.run.exit_code), c.verdict, cell(c.reason),
                          format_number(c.run.wall_s), format_number(c.scene.duration_s),
                          format_number(c.run.wall_s / c.scene.duration_s), format_number(c.max_force_n),
                          format_number(c.clamp_n), std::to_string(c.newton_failures), std::to_string(c.unstable_frames)});
  }
  write_csv(table, out / "table.csv");
  const double n = std::max<double>(1, outcomes.size());
  char figures[256];
  std::snprintf(figures, sizeof figures, "%ld of %zu scenes ran to their end (%.1f %%), %ld failed with a physical reason, %ld defects",
                ran, outcomes.size(), 100 * ran / n, failed, defects);
  std::ostringstream md;
  md << "# Hard cases: " << outcomes.size() << " valid scenes drawn with seed " << o.seed << "\n\n"
     << "Each scene (`scenes/NAME/scene.yaml`, drawn by `app/study/random_scenes.cc`) replayed by `fetouch replay` in a "
        "process of its own. A scene must run to its end (forces finite and within the clamp, no frame with unstable "
        "gains) or fail with exit 1 and a physical reason; anything else is a defect.\n\n"
     << figures << ". P1 replays over 10x their simulated time: " << slow << " of " << p1 << ".\n\n";
  md << "| scene | tissue and probes | verdict | reason | wall (s) | simulated (s) | max force (N) | Newton failures |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const Outcome& c : outcomes) {
    char row[128];
    std::snprintf(row, sizeof row, "%.1f | %.2f | %.3f | %ld", c.run.wall_s, c.scene.duration_s, c.max_force_n, c.newton_failures);
    md << "| " << c.scene.name << " | " << c.scene.summary << " | " << (c.verdict == "DEFECT" ? "**DEFECT**" : c.verdict) << " | "
       << c.reason << " | " << row << " |\n";
  }
  if (failed + defects > 0) {
    md << "\n## Not run to the end\n\n";
    for (const Outcome& c : outcomes)
      if (c.verdict != "ran") md << "- `" << c.file.string() << "`: " << c.verdict << ": " << c.reason << "\n";
  }
  write_text_file(out / "report.md", md.str());
  std::ostringstream json_text;
  JsonWriter json(json_text);
  json.begin_object().key("seed").value(static_cast<long>(o.seed)).key("scenes").value(static_cast<long>(outcomes.size()));
  json.key("ran").value(ran).key("failed").value(failed).key("defects").value(defects);
  json.key("p1_over_10x").value(slow).key("runs").begin_array();
  for (const Outcome& c : outcomes)
    json.begin_object().key("scene").value(c.file.string()).key("summary").value(c.scene.summary).key("exit").value(static_cast<long>(c.run.exit_code))
        .key("verdict").value(c.verdict).key("reason").value(c.reason).key("wall_s").value(c.run.wall_s)
        .key("simulated_s").value(c.scene.duration_s).key("p1").value(c.scene.p1).key("max_force_n").value(c.max_force_n)
        .key("clamp_n").value(c.clamp_n).key("newton_failures").value(c.newton_failures)
        .key("unstable_frames").value(c.unstable_frames).end_object();
  json.end_array().end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), o.json)) std::printf("%s; wrote %s\n", figures, (out / "report.md").string().c_str());
  return defects == 0 ? kExitOk : kExitFailure;
}

}  // namespace fetouch::app
