// fetouch-gui: the command line with every command, those that draw (Qt, VTK's rendering) included;
// `fetouch` runs it for them (app/cli.h).
#include <CLI/CLI.hpp>

#include <cstring>

#include "app/cli.h"
#include "app/commands/commands.h"

namespace {

void add_drawing_command(const char* name, CLI::App& app, int& exit_code) {
  using namespace fetouch::app;
  if (std::strcmp(name, "stability") == 0) add_stability_command(app, exit_code);
  if (std::strcmp(name, "render") == 0) add_render_command(app, exit_code);
  if (std::strcmp(name, "trainer") == 0) add_trainer_command(app, exit_code);
  if (std::strcmp(name, "review") == 0) add_review_command(app, exit_code);
  if (std::strcmp(name, "study") == 0) add_study_command(app, exit_code);
}

}  // namespace

int main(int argc, char** argv) { return fetouch::app::run_cli(argc, argv, add_drawing_command); }
