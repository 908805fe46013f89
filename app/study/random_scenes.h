// Valid scenes drawn at random from the schema (docs/scenes.md), for `fetouch study hard-cases
// --random N --seed S` and the test suite: generated tissues (box, ball, shell; every element,
// material model, effect, integrator, support type, solver, local model, hold, probe device that
// runs headless), trajectories that poke, slide and squeeze, fast and slow. Every enum value is
// taken in turn (scene i takes value (i + offset) mod count, the offset drawn from the seed), so
// any run of at least six scenes holds each value of every enum of up to six values; numbers are
// drawn from their ranges with their edges favoured. The same seed and index give the same scene.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "haptics/devices.h"

namespace fetouch::app {

struct RandomScene {
  std::string name;  // scene_SEED_INDEX
  std::string yaml;  // the scene file's text; trajectories named relative to it
  std::vector<std::pair<std::string, haptics::Trajectory>> trajectories;  // file name, path
  std::string summary;  // one line: tissue, element, material, effects, probes, local model
  bool p1 = false;      // P1 elements (the replay's time bound applies to these)
  double duration_s = 0;  // of the longest trajectory
};

RandomScene random_scene(unsigned int seed, int index);

// Writes DIR/scene.yaml and its trajectories; returns the scene file.
std::filesystem::path write_random_scene(const RandomScene& scene, const std::filesystem::path& dir);

}  // namespace fetouch::app
