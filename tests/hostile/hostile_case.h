// The hostile-input regression suite (issue 17): broken inputs of every kind Fetouch reads, each
// run through the real `fetouch` binary. A case writes its inputs into an empty folder and says how
// to call fetouch on them and what must come back: the exit code, and the file or option the one-
// line message must name. The test adds what holds for every case: no signal, no timeout, no input
// changed, no raw exception or library text as the message, no more than a screen of it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace fetouch::testing::hostile {

namespace fs = std::filesystem;

struct Invocation {
  std::vector<std::string> args;  // fetouch's arguments (no shell: names reach it as they are)
  std::string names;              // the message names this (a file's name or an option); "" for exit 0
  int exit_code = 2;
};

struct Case {
  std::string name;    // unique: [A-Za-z0-9_]
  std::string kind;    // scene, volume, mesh, trajectory, recording, calibration, command line
  std::string guards;  // what such input did before issue 17: crash, hang, overwrite, nonsense, unclear, or valid
  std::string form;    // malformed, truncated, huge, special file, non-finite, absurd, wrong shape, name, output over input
  std::function<Invocation(const fs::path& dir)> make;
};

std::vector<Case> scene_cases();
std::vector<Case> mesh_cases();
std::vector<Case> volume_cases();
std::vector<Case> trajectory_cases();
std::vector<Case> recording_cases();
std::vector<Case> calibration_cases();
std::vector<Case> command_line_cases();
std::vector<Case> all_cases();

// Helpers for the generators.
fs::path source_dir();
std::string read_text(const fs::path& file);
void write_text(const fs::path& file, const std::string& text);
void make_fifo(const fs::path& file);
void make_sparse(const fs::path& file, std::uintmax_t bytes);  // a huge file that takes no disk
std::string replaced(std::string text, const std::string& from, const std::string& to);  // throws if absent
std::string garbage(std::size_t bytes, std::uint32_t seed);  // reproducible random bytes

// The block scene (config/scenes/block_press.yaml) with its trajectory beside it in `dir`;
// returns the scene's path. `edit` changes its text first.
// A small tracked sweep (PLUS .igs.mha) and a calibration that reconstruct accepts.
std::string sweep_text();
std::string calibration_text();

fs::path write_block_scene(const fs::path& dir, const std::string& file_name = "scene.yaml",
                           const std::function<std::string(std::string)>& edit = {});

}  // namespace fetouch::testing::hostile
