// Every broken scene under tests/config/broken is rejected by the loader with an error at the line
// marked in the file, naming the key and saying what the file's header expects.
#include <gtest/gtest.h>

#include <algorithm>

#include "config/scene_loader.h"
#include "tests/support/broken_scene.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

class BrokenScene : public ::testing::TestWithParam<std::filesystem::path> {};

TEST_P(BrokenScene, RejectedAtTheMarkedLineWithTheKey) {
  const BrokenSceneExpectation expected = read_expectation(GetParam());
  ASSERT_GT(expected.line, 0) << "the file has no '# <-- error' marker";
  if (expected.needs_mesh) {
    // Valid as a file; only `fetouch check` sees the problem, with the mesh (see cli_tests).
    EXPECT_NO_THROW(config::load_scene(expected.file));
    return;
  }
  try {
    config::load_scene(expected.file);
    FAIL() << expected.file << " was accepted";
  } catch (const config::SceneError& error) {
    const auto& all = error.diagnostics();
    const bool found = std::any_of(all.begin(), all.end(), [&](const config::Diagnostic& d) {
      return d.severity == config::Diagnostic::Severity::error && d.line == expected.line &&
             d.key == expected.key && d.message.find(expected.message) != std::string::npos &&
             d.column > 0;
    });
    EXPECT_TRUE(found) << "expected an error at line " << expected.line << " on key '"
                       << expected.key << "' saying '" << expected.message << "'; got:\n"
                       << error.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Files, BrokenScene, ::testing::ValuesIn(broken_scene_files()),
                         [](const auto& param_info) { return scene_test_name(param_info.param); });

TEST(BrokenScenes, AtLeastTwentyFiveAndTheBaseIsValid) {
  EXPECT_GE(broken_scene_files().size(), 25u);
  // Each broken file is this base with one thing broken, so the base must pass.
  EXPECT_NO_THROW(config::load_scene(std::filesystem::path(FETOUCH_TEST_DATA_DIR) / "config/valid/base.yaml"));
}

}  // namespace
}  // namespace fetouch::testing
