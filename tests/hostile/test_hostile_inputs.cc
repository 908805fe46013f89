// Issue 17's hostile-input regression suite: every generated broken input through the real fetouch.
// For each case: the expected exit code; no signal and no timeout (60 s); the message names the
// offending file or option, is not a raw exception or library text and fits a screen; and every file
// that was in the case's folder before the run is byte for byte the same after it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "tests/hostile/hostile_case.h"
#include "tests/hostile/run_process.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing::hostile {
namespace {

constexpr double kTimeLimitS = 60;
constexpr std::uintmax_t kCompareWhole = 64u << 20;  // larger (sparse) inputs: size and both ends

struct Snapshot {
  std::uintmax_t size = 0;
  std::string head, tail;  // the whole file when it is small
};

std::map<fs::path, Snapshot> snapshot(const fs::path& dir) {
  std::map<fs::path, Snapshot> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file() || entry.is_symlink()) continue;
    Snapshot s;
    s.size = entry.file_size();
    std::ifstream in(entry.path(), std::ios::binary);
    const std::uintmax_t part = s.size <= kCompareWhole ? s.size : (1u << 20);
    s.head.resize(part);
    in.read(s.head.data(), static_cast<std::streamsize>(part));
    if (s.size > kCompareWhole) {
      s.tail.resize(part);
      in.seekg(static_cast<std::streamoff>(s.size - part));
      in.read(s.tail.data(), static_cast<std::streamsize>(part));
    }
    files[entry.path()] = std::move(s);
  }
  return files;
}

// Texts that mean a crash, a sanitizer finding, or a raw library or exception message reached the user.
const char* const kForbidden[] = {
    "terminate called", "what():", "AddressSanitizer", "runtime error:", "Segmentation fault", "Aborted",
    "std::", "basic_string", "vector::", "bad_alloc", "stod", "stoi", "--------------------",
    "HDF5-DIAG", "ERROR: In ", "Warning: In ", " (0x", "M_Read", "MetaObject:", "Gmsh:", "An error occurred in line"};

class HostileInput : public ::testing::TestWithParam<Case> {};

TEST_P(HostileInput, RefusedCleanlyAndInputsKept) {
  const Case& c = GetParam();
  const fs::path dir = fs::temp_directory_path() / ("fetouch_hostile_" + std::to_string(::getpid()) + "_" + c.name);
  fs::remove_all(dir);
  fs::create_directories(dir / ".capture");
  const Invocation run = c.make(dir);
  const auto before = snapshot(dir);

  std::vector<std::string> argv{FETOUCH_BINARY};
  argv.insert(argv.end(), run.args.begin(), run.args.end());
  const ProcessResult r = run_process(argv, dir, dir / ".capture", kTimeLimitS);
  // FETOUCH_HOSTILE_LOG=DIR keeps every case's messages (DIR/NAME.txt) to read them all at once.
  if (const char* log = std::getenv("FETOUCH_HOSTILE_LOG"))
    std::ofstream(fs::path(log) / (c.name + ".txt")) << "exit " << r.exit_code << " signal " << r.signal << " in " << r.seconds
                                                      << " s\n" << r.err;
  std::string shown;
  for (std::size_t i = 1; i < argv.size(); ++i) shown += " " + (argv[i].size() > 120 ? argv[i].substr(0, 120) + "..." : argv[i]);
  SCOPED_TRACE("[" + c.kind + ", " + c.form + "] fetouch" + shown + "\n--- stderr:\n" + r.err.substr(0, 1500));

  EXPECT_FALSE(r.timed_out) << "ran past " << kTimeLimitS << " s";
  EXPECT_EQ(r.signal, 0) << "ended by signal " << r.signal;
  EXPECT_EQ(r.exit_code, run.exit_code) << "in " << r.seconds << " s";
  EXPECT_LE(r.err.size(), 4000u) << "more than a screen of text";
  if (run.exit_code != 0 && r.exit_code == run.exit_code) {
    // An error line names the file or option (not just a progress line such as "reading FILE").
    bool named = false;
    std::istringstream lines(r.err);
    for (std::string line; std::getline(lines, line);)
      named = named || (line.find("error") != std::string::npos && line.find(run.names) != std::string::npos);
    EXPECT_TRUE(named) << "no error line names '" << run.names << "'";
    EXPECT_LE(std::count(r.err.begin(), r.err.end(), '\n'), 25) << "more than a screen of text";
  }
  for (const char* text : kForbidden) EXPECT_EQ(r.err.find(text), std::string::npos) << "the message holds '" << text << "'";

  for (const auto& [path, was] : before) {
    if (path.parent_path() == dir / ".capture") continue;
    const auto now = snapshot(path.parent_path());
    const auto found = now.find(path);
    ASSERT_NE(found, now.end()) << path << " (an input) is gone";
    EXPECT_TRUE(found->second.size == was.size && found->second.head == was.head && found->second.tail == was.tail)
        << path << " (an input) was changed";
  }
  if (!HasFailure()) fs::remove_all(dir);
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) { return info.param.name; }

}  // namespace

// How gtest prints a case (in test names and failures): its name.
void PrintTo(const Case& c, std::ostream* out) { *out << c.name; }

namespace {

INSTANTIATE_TEST_SUITE_P(Cases, HostileInput, ::testing::ValuesIn(all_cases()), case_name);

// The suite covers what the issue asks: at least 200 cases, every kind and every category it lists
// (crashes, hangs, overwritten inputs, accepted nonsense, unclear errors) five times or more. Prints
// the table of cases by kind and expected outcome that docs/hostile_inputs.md shows.
TEST(HostileSuite, CoversEveryKindAndCategory) {
  const auto cases = all_cases();
  EXPECT_GE(cases.size(), 200u);
  std::set<std::string> names;
  std::map<std::string, std::map<std::string, int>> by_kind, by_category;
  const fs::path scratch = fs::temp_directory_path() / ("fetouch_hostile_table_" + std::to_string(::getpid()));
  for (const Case& c : cases) {
    EXPECT_TRUE(names.insert(c.name).second) << "two cases named " << c.name;
    fs::remove_all(scratch);
    fs::create_directories(scratch);
    const Invocation run = c.make(scratch);
    if (run.exit_code != 0) {
      EXPECT_FALSE(run.names.empty()) << c.name << " names nothing to look for";
    }
    const std::string outcome = run.exit_code == 0 ? "accepted (0)" : run.exit_code == 1 ? "failed (1)" : "refused (2)";
    ++by_kind[c.kind][outcome], ++by_kind[c.kind]["all"];
    ++by_category[c.guards][c.kind], ++by_category[c.guards]["all"];
  }
  fs::remove_all(scratch);
  for (const char* category : {"crash", "hang", "overwrite", "nonsense", "unclear"})
    EXPECT_GE(by_category[category]["all"], 5) << category;
  for (const char* kind : {"scene", "volume", "mesh", "trajectory", "recording", "calibration", "command line"})
    EXPECT_GE(by_kind[kind]["all"], 5) << kind;

  std::printf("| kind | cases | refused (2) | failed (1) | accepted (0) |\n|---|---|---|---|---|\n");
  for (auto& [kind, counts] : by_kind)
    std::printf("| %s | %d | %d | %d | %d |\n", kind.c_str(), counts["all"], counts["refused (2)"], counts["failed (1)"],
                counts["accepted (0)"]);
  std::printf("\n| what such input did before | cases |\n|---|---|\n");
  for (auto& [category, counts] : by_category) std::printf("| %s | %d |\n", category.c_str(), counts["all"]);
  std::printf("\n%zu cases\n", cases.size());
}

}  // namespace
}  // namespace fetouch::testing::hostile
