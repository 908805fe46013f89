// The expectation a broken scene file states about itself: its header names the key and a piece of
// the message, and the offending line carries the marker "# <-- error". The expected line number is
// therefore read from the file's text, independently of the program under test.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/test_paths.h"

namespace fetouch::testing {

struct BrokenSceneExpectation {
  std::filesystem::path file;
  int line = 0;
  std::string key;
  std::string message;
  bool needs_mesh = false;  // "expect-stage: check": only the mesh-level checks of `fetouch check` see it
};

inline BrokenSceneExpectation read_expectation(const std::filesystem::path& file) {
  BrokenSceneExpectation e;
  e.file = file;
  std::ifstream in(file);
  std::string text;
  const auto value_after = [](const std::string& line, const std::string& tag) {
    return line.substr(line.find(tag) + tag.size());
  };
  for (int number = 1; std::getline(in, text); ++number) {
    if (text.rfind("# expect-key: ", 0) == 0) e.key = value_after(text, "# expect-key: ");
    else if (text.rfind("# expect-key:", 0) == 0) e.key = "";
    if (text.rfind("# expect-message: ", 0) == 0) e.message = value_after(text, "# expect-message: ");
    if (text.rfind("# expect-stage: check", 0) == 0) e.needs_mesh = true;
    if (text.find("# <-- error") != std::string::npos) e.line = number;
  }
  return e;
}

inline std::vector<std::filesystem::path> broken_scene_files() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(FETOUCH_TEST_DATA_DIR) / "config/broken"))
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// gtest parameter names: the file's stem.
inline std::string scene_test_name(const std::filesystem::path& file) { return file.stem().string(); }

}  // namespace fetouch::testing
