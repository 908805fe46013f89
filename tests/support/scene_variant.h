// A shipped scene with one setting changed, written elsewhere (tests only).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/run_command.h"

namespace fetouch::testing {

// Writes `scene`'s text with the first `from` replaced by `to` to `out`, its trajectories named
// by absolute path (they are relative to the scene's folder). False, writing nothing, when the
// scene has no `from`.
inline bool write_scene_variant(const std::filesystem::path& scene, const std::string& from, const std::string& to,
                                const std::filesystem::path& out) {
  std::string text = read_file_text(scene);
  const std::size_t at = text.find(from);
  if (at == std::string::npos) return false;
  text.replace(at, from.size(), to);
  const std::string relative = " trajectories/", absolute = " " + (scene.parent_path() / "trajectories").string() + "/";
  for (std::size_t t; (t = text.find(relative)) != std::string::npos;) text.replace(t, relative.size(), absolute);
  std::ofstream(out) << text;
  return true;
}

}  // namespace fetouch::testing
