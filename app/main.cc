// fetouch: the command-line entry point. Everything lives in app/cli.cc and app/commands/.
#include "app/cli.h"

int main(int argc, char** argv) { return fetouch::app::run_cli(argc, argv); }
