#include "app/cli.h"

#include <CLI/CLI.hpp>
#include <vtkLogger.h>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>

#include "app/build_info.h"
#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/log.h"

namespace fetouch::app {

namespace {

std::string version_text() {
  return std::string("fetouch ") + kVersion + " (git " + kGitRevision + ", " + kBuildType +
         ", " + kCompiler + ", deal.II " + kDealIIVersion + ", VTK " + kVtkVersion + ")";
}

bool is_number(const char* text) {
  char* end = nullptr;
  std::strtod(text, &end);
  return end != text && *end == '\0';
}

// The index of the first argument that is a number but not a finite one ("nan", "inf", "1e400"),
// or 0: no value of any option may be one, and CLI11 would take it (a NaN passes every range check).
int first_non_finite(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(argv[i], &end);
    if (end != argv[i] && *end == '\0' && (!std::isfinite(x) || (errno == ERANGE && std::abs(x) > 1))) return i;
  }
  return 0;
}

// `fetouch COMMAND ...` for a command that draws: the same arguments to fetouch-gui beside this
// executable. Returns only when it cannot be executed.
int run_drawing_command(const char* command, char** argv) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::filesystem::path gui = (error ? std::filesystem::path(argv[0]).parent_path() : self.parent_path()) / "fetouch-gui";
  execv(gui.c_str(), argv);
  std::cerr << "error: `fetouch " << command << "` draws with Qt and VTK, which live in " << gui.string()
            << " beside fetouch, and that could not be run: " << std::strerror(errno) << "\n";
  return kExitFailure;
}

}  // namespace

const char* drawing_command_description(const char* name) {
  for (const DrawingCommand& c : kDrawingCommands)
    if (std::strcmp(c.name, name) == 0) return c.description;
  return "";
}

int run_cli(int argc, char** argv, AddDrawingCommand add_drawing_command) {
  CLI::App app{
      "Fetouch: touch soft tissue reconstructed from 3D ultrasound through haptic devices, with a\n"
      "nonlinear finite-element model behind the touch.\n"
      "\n"
      "Start with `fetouch check config/scenes/block_press.yaml`; `fetouch COMMAND --help` tells\n"
      "more about each command. Exit codes: 0 ok, 1 the work failed, 2 bad usage or bad input.",
      "fetouch"};
  app.set_version_flag("--version", version_text(), "Print the version and git revision, then exit");
  int verbosity = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbosity, "More detail on stderr (-vv for debugging)");
  app.add_flag("-q,--quiet", quiet, "Only errors on stderr");
  app.require_subcommand(1);
  app.fallthrough();  // -v and -q work after the subcommand too
  app.footer("Documentation: README.md and docs/ in the source tree.");

  int exit_code = kExitOk;
  // A command that draws: itself in fetouch-gui; in fetouch listed, and run by fetouch-gui (below).
  const auto drawing = [&](const char* name) {
    if (add_drawing_command) add_drawing_command(name, app, exit_code);
    else app.add_subcommand(name, drawing_command_description(name))->allow_extras();
  };
  add_check_command(app, exit_code);
  drawing("stability");
  add_solve_command(app, exit_code);
  add_phantom_command(app, exit_code);
  add_reconstruct_command(app, exit_code);
  add_mesh_command(app, exit_code);
  add_labels_command(app, exit_code);
  drawing("render");
  add_replay_command(app, exit_code);
  add_run_command(app, exit_code);
  add_devices_command(app, exit_code);
  drawing("trainer");
  drawing("review");
  add_trajectory_command(app, exit_code);
  drawing("study");

  app.parse_complete_callback([&]() {
    if (quiet) log::set_level(log::Level::error);
    else if (verbosity >= 2) log::set_level(log::Level::debug);
    else if (verbosity == 1) log::set_level(log::Level::detail);
    // VTK's own messages (a reader's complaint, an allocation that failed) are for debugging: the
    // commands catch the errors and say what is wrong in one line (-vv shows VTK's text too).
    if (verbosity < 2) vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  });

  // An unknown command: CLI11 would only say that a subcommand is required.
  // The first word that is not an option (-v, -q, --help and --version take no value) is the command.
  const char* const* word = std::find_if(argv + 1, argv + argc, [](const char* a) { return a[0] != '-' && a[0] != '\0'; });
  if (word != argv + argc) {
    std::string known;
    bool found = false;
    for (const CLI::App* command : std::as_const(app).get_subcommands([](const CLI::App*) { return true; })) {
      known += (known.empty() ? "" : ", ") + command->get_name();
      found = found || command->get_name() == *word;
    }
    if (!found) {
      std::cerr << "error: unknown command '" << *word << "'; the commands are " << known
                << ".\nRun `fetouch --help` for what each does.\n";
      return kExitBadInput;
    }
    if (!add_drawing_command)
      for (const DrawingCommand& c : kDrawingCommands)
        if (std::strcmp(c.name, *word) == 0) return run_drawing_command(c.name, argv);
  }
  if (const int bad = first_non_finite(argc, argv)) {
    std::string option = "argument " + std::to_string(bad);
    for (int k = bad - 1; k >= 1; --k)
      if (argv[k][0] == '-' && !is_number(argv[k])) {
        option = argv[k];
        break;
      }
    std::cerr << "error: " << option << ": " << argv[bad] << " is not a finite number\n";
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e) == 0 ? kExitOk : kExitBadInput;
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e) == 0 ? kExitOk : kExitBadInput;
  } catch (const CLI::CallForVersion& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();  // it quotes the argument: a megabyte of it is no message
    if (what.size() > 300) what = what.substr(0, 297) + "...";
    std::cerr << "error: " << what << "\nRun `fetouch --help` (or `fetouch COMMAND --help`) "
                                         "for usage.\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    log::error() << e.what();
    return kExitFailure;
  }
  return exit_code;
}

}  // namespace fetouch::app
