// The `fetouch` command line: global options, the subcommands, and the mapping of failures onto the
// exit codes of exit_codes.h.
#pragma once

namespace fetouch::app {

int run_cli(int argc, char** argv);

}  // namespace fetouch::app
