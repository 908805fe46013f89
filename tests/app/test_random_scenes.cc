// The scenes `fetouch study hard-cases --random` draws are valid by the loader, the same for the same
// seed, and cover every enum value that docs/scenes.md documents and the loader accepts (the
// headless ones: see kNotDrawn).
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>


#include "app/study/random_scenes.h"
#include "config/scene_loader.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/test_paths.h"

namespace fetouch::app {
namespace {

using fetouch::testing::ScratchDir;

constexpr int kScenes = 24;  // what the CI run of the study draws (tests/app/test_study_command.cc)

// Documented values a drawn scene does not take, and why.
const std::map<std::string, std::string> kNotDrawn = {
    {"device.type: phantom", "needs a PHANTOM (its stand-in is driven by tests/devices)"},
    {"device.type: mouse", "interactive: the trainer's"},
    {"smoothing: none", "volume meshing (tests/app/test_mesh_command.cc), not a generated tissue"},
    {"smoothing: gaussian", "volume meshing"},
    {"smoothing: median", "volume meshing"},
    {"surface: restricted", "volume meshing"},
    {"surface: contoured", "volume meshing"},
    {"surface: conforming", "volume meshing (tests/meshes/test_labeled_mesher.cc, tests/app/test_mesh_command.cc)"},
};

std::vector<RandomScene> drawn(unsigned int seed) {
  std::vector<RandomScene> scenes;
  for (int i = 0; i < kScenes; ++i) scenes.push_back(random_scene(seed, i));
  return scenes;
}

// The scene loaded as `fetouch replay` loads it: from its file, beside its trajectories.
config::Scene load(const RandomScene& s, const ScratchDir& scratch) {
  return config::load_scene(write_random_scene(s, scratch / s.name)).scene;
}

// `key: value` in a scene's text, the value ending there.
bool says(const std::string& text, const std::string& key, const std::string& value) {
  const std::string needle = key + ": " + value;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) {
    const std::size_t end = at + needle.size();
    const bool key_starts = at == 0 || !(std::isalnum(static_cast<unsigned char>(text[at - 1])) || text[at - 1] == '_');
    const bool value_ends = end == text.size() || !(std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_');
    if (key_starts && value_ends) return true;
  }
  return false;
}

TEST(RandomScenes, EveryDrawnSceneIsValidAndTheSeedFixesIt) {
  const ScratchDir scratch("fetouch_random_scenes");
  for (const RandomScene& s : drawn(7)) {
    try {
      load(s, scratch);
    } catch (const config::SceneError& e) {
      ADD_FAILURE() << e.what() << "\n" << s.yaml;
    }
    EXPECT_EQ(random_scene(7, std::stoi(s.name.substr(s.name.rfind('_') + 1))).yaml, s.yaml);
    EXPECT_GT(s.duration_s, 0);
  }
  EXPECT_NE(random_scene(7, 3).yaml, random_scene(8, 3).yaml);
}

// docs/scenes.md's tables: every row whose type is a list of values (`a`, `b`, ...).
TEST(RandomScenes, EveryDocumentedValueIsDrawn) {
  std::ifstream docs(std::filesystem::path(FETOUCH_SOURCE_DIR) / "docs" / "scenes.md");
  ASSERT_TRUE(docs) << "docs/scenes.md";
  const std::regex row(R"(^\| `([a-z_.]+)` \| ((`[^`]+`)(, `[^`]+`)*) \|)"), value("`([^`]+)`");
  std::string all;
  for (const RandomScene& s : drawn(1)) all += s.yaml + "\n";
  int checked = 0;
  for (std::string line; std::getline(docs, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    const std::string key = m[1], values = m[2];
    const std::string last = key.substr(key.rfind('.') == std::string::npos ? 0 : key.rfind('.') + 1);
    for (std::sregex_iterator v(values.begin(), values.end(), value), end; v != end; ++v) {
      const std::string documented = key + ": " + (*v)[1].str();
      if (kNotDrawn.count(documented)) continue;
      EXPECT_TRUE(says(all, last, (*v)[1].str())) << documented << " is documented but no drawn scene takes it";
      ++checked;
    }
  }
  EXPECT_GE(checked, 25);  // the tables' enum values: units, element, shape, type, solver, model, hold, coupling, device
}

// The loader's own enums, through the parsed scenes: what docs/scenes.md lists outside its tables.
TEST(RandomScenes, EveryEnumOfTheLoaderIsDrawn) {
  const ScratchDir scratch("fetouch_random_scenes");
  std::set<std::string> seen;
  for (const RandomScene& s : drawn(1)) {
    const config::Scene scene = load(s, scratch);
    seen.insert(std::string("model ") + config::to_string(scene.material.model));
    if (scene.effects.has(config::Effect::inertia)) seen.insert(std::string("integrator ") + config::to_string(scene.effects.integrator));
    if (scene.effects.has(config::Effect::cavity)) seen.insert(std::string("law ") + config::to_string(scene.effects.cavity_law));
    for (const config::Effect e : scene.effects.listed) seen.insert(std::string("effect ") + config::to_string(e));
    for (const config::BoundaryRegion& b : scene.boundary) seen.insert(std::string("selector ") + config::to_string(b.select.kind));
    seen.insert(std::string("line_search ") + (scene.solver.line_search ? "true" : "false"));
  }
  for (const char* expected :
       {"model linear_elastic", "model saint_venant_kirchhoff", "model neo_hookean", "model neo_hookean_incompressible",
        "model mooney_rivlin", "integrator backward_euler", "integrator newmark", "integrator hht", "law linear",
        "law isothermal_gas", "effect gravity", "effect inertia", "effect damping", "effect incompressibility",
        "effect cavity", "effect contact", "selector box", "selector physical_group", "selector plane",
        "line_search true", "line_search false"})
    EXPECT_TRUE(seen.count(expected)) << expected << " is accepted by the loader but no drawn scene takes it";
}

}  // namespace
}  // namespace fetouch::app
