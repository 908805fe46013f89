// The `fetouch` command line: global options, the subcommands, and the mapping of failures onto the
// exit codes of exit_codes.h.
//
// Two executables share it. `fetouch-gui` has every command. `fetouch` leaves out the commands that
// draw (Qt and VTK's rendering: a third of the shared libraries the process would load, 50 ms of
// every start): it lists them, and runs them by executing `fetouch-gui` beside it with the same
// arguments.
#pragma once

namespace CLI {
class App;
}

namespace fetouch::app {

// Registers the command that draws named `name` (one of kDrawingCommands).
using AddDrawingCommand = void (*)(const char* name, CLI::App& parent, int& exit_code);

// The commands that draw: their names and one-line descriptions.
struct DrawingCommand {
  const char* name;
  const char* description;
};
inline constexpr DrawingCommand kDrawingCommands[] = {
    {"stability", "Analyse the stability of a local model on a tissue"},
    {"render", "Draw a mesh or a volume's middle slice to a PNG"},
    {"trainer", "The trainer window: touch the tissue, see it deform and its ultrasound"},
    {"review", "Play a recorded take back: the probe paths and forces over the anatomy, the scores"},
    {"study", "Studies of a scene: accuracy against time, effects' costs, hard cases"},
};
const char* drawing_command_description(const char* name);

// `add_drawing_command` registers the commands that draw (fetouch-gui); null: `fetouch`, which
// lists them and executes fetouch-gui for them.
int run_cli(int argc, char** argv, AddDrawingCommand add_drawing_command);

}  // namespace fetouch::app
