// Reading a scene file: YAML in, a validated Scene out, or a SceneError listing every problem with
// file:line:column, the dotted key, what was expected and the closest valid key for a typo.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "config/diagnostics.h"
#include "config/scene.h"

namespace fetouch::config {

struct LoadedScene {
  Scene scene;
  std::vector<Diagnostic> warnings;  // things that are allowed but probably not meant
};

// Reads and validates `file`. Throws SceneError when the file cannot be read or has any error.
LoadedScene load_scene(const std::filesystem::path& file);

// The same from text; `label` names the text in messages, relative paths resolve against `base_dir`.
LoadedScene parse_scene(const std::string& text, const std::string& label,
                        const std::filesystem::path& base_dir);

}  // namespace fetouch::config
