// fetouch: the command-line entry point, without the commands that draw (app/cli.h): they run in
// fetouch-gui. Everything lives in app/cli.cc and app/commands/.
#include "app/cli.h"

int main(int argc, char** argv) { return fetouch::app::run_cli(argc, argv, nullptr); }
