// The fetouch binary as a user meets it: version, help on every command, exit codes.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>

#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

TEST(Cli, VersionNamesTheGitRevision) {
  const auto r = run_command(fetouch("--version"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(^fetouch \d+\.\d+\.\d+ \(git \S+)")))
      << r.out;
  // Cross-check with git itself where the source is a git checkout.
  const auto head = run_command("git -C " + std::string(FETOUCH_SOURCE_DIR) +
                                " rev-parse --short=12 HEAD");
  if (head.exit_code == 0 && !head.out.empty()) {
    const std::string hash = head.out.substr(0, head.out.find('\n'));
    EXPECT_NE(r.out.find(hash), std::string::npos) << r.out << " does not name " << hash;
  }
}

TEST(Cli, HelpForTheProgramAndEachCommand) {
  const auto top = run_command(fetouch("--help"));
  EXPECT_EQ(top.exit_code, 0);
  EXPECT_NE(top.out.find("Subcommands:"), std::string::npos);
  EXPECT_NE(top.out.find("Exit codes"), std::string::npos);
  // Every subcommand listed in the top-level help has its own help.
  const std::string listing = top.out.substr(top.out.find("Subcommands:"));
  std::regex row(R"(\n  ([a-z]+)\s+\S)");
  int commands = 0;
  for (std::sregex_iterator it(listing.begin(), listing.end(), row), end; it != end; ++it) {
    const std::string command = (*it)[1];
    ++commands;
    const auto help = run_command(fetouch(command + " --help"));
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.out.find("Usage: fetouch " + command), std::string::npos) << help.out;
    EXPECT_EQ(help.out.find("not implemented"), std::string::npos) << command;
  }
  EXPECT_GE(commands, 1);
}

// `fetouch` itself loads neither Qt nor VTK's rendering (a third of the libraries, 50 ms of every
// start); the commands that draw run in fetouch-gui beside it, with the same arguments and exit code.
TEST(Cli, TheCommandsThatDrawRunInFetouchGuiAndTheRestLoadNoGui) {
  const auto libraries = run_command("LD_DEBUG=libs " + fetouch("--version"));
  EXPECT_EQ(libraries.exit_code, 0);
  EXPECT_NE(libraries.err.find("libdeal.ii"), std::string::npos) << "LD_DEBUG shows no library loaded";
  EXPECT_EQ(libraries.err.find("libQt5"), std::string::npos);
  EXPECT_EQ(libraries.err.find("libvtkRenderingOpenGL2"), std::string::npos);
  const auto render = run_command("LD_DEBUG=libs " + fetouch("render --help"));
  EXPECT_EQ(render.exit_code, 0);
  EXPECT_NE(render.out.find("Usage: fetouch render"), std::string::npos) << render.out;
  EXPECT_NE(render.err.find("libvtkRenderingOpenGL2"), std::string::npos) << "render did not run in fetouch-gui";
  const auto bad = run_command(fetouch("study effects " + std::string(FETOUCH_SOURCE_DIR) +
                                       "/config/scenes/block_press.yaml --no-such-option"));
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--no-such-option"), std::string::npos) << bad.err;
}

TEST(Cli, BadUsageExitsTwoWithAHint) {
  for (const char* arguments : {"", "frobnicate", "check", "check --no-such-option x.yaml"}) {
    const auto r = run_command(fetouch(arguments));
    EXPECT_EQ(r.exit_code, 2) << arguments;
    EXPECT_NE(r.err.find("--help"), std::string::npos) << arguments << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << arguments;  // errors on stderr, never stdout
  }
  // An unknown command is named, with the commands there are (issue 17: "A subcommand is required").
  const auto unknown = run_command(fetouch("-v frobnicate x.yaml"));
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("unknown command 'frobnicate'"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("check, stability, solve"), std::string::npos) << unknown.err;
  // A number that is not one (issue 17: exit 1 and no message for a NaN --press).
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const auto nan = run_command(fetouch("solve " + scene + " --out /tmp/fetouch_nan_press --press 0.05 0.04 0.05 0 0 nan"));
  EXPECT_EQ(nan.exit_code, 2);
  EXPECT_NE(nan.err.find("--press: nan is not a finite number"), std::string::npos) << nan.err;
  EXPECT_FALSE(std::filesystem::exists("/tmp/fetouch_nan_press"));
}

TEST(Cli, QuietAndVerboseWorkBeforeOrAfterTheCommand) {
  const std::string scene = std::string(FETOUCH_SOURCE_DIR) + "/config/scenes/block_press.yaml";
  const auto verbose = run_command(fetouch("check -v " + scene));
  EXPECT_EQ(verbose.exit_code, 0);
  EXPECT_NE(verbose.err.find("checking"), std::string::npos) << verbose.err;
  const auto quiet = run_command(fetouch("-q check " + scene));
  EXPECT_EQ(quiet.exit_code, 0);
  EXPECT_TRUE(quiet.err.empty()) << quiet.err;
}

}  // namespace
}  // namespace fetouch::testing
