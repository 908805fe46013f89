#include <sys/stat.h>

#include <cctype>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "tests/hostile/hostile_case.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing::hostile {

fs::path source_dir() { return FETOUCH_SOURCE_DIR; }

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& file, const std::string& text) {
  if (file.has_parent_path()) fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

void make_fifo(const fs::path& file) {
  if (::mkfifo(file.c_str(), 0644) != 0) throw std::runtime_error("cannot make the FIFO " + file.string());
}

void make_sparse(const fs::path& file, std::uintmax_t bytes) {
  write_text(file, "");
  fs::resize_file(file, bytes);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("the generator's base text has no '" + from + "'");
  return text.replace(at, from.size(), to);
}

std::string garbage(std::size_t bytes, std::uint32_t seed) {
  std::mt19937 random(seed);
  std::string out(bytes, '\0');
  for (char& c : out) c = static_cast<char>(random() & 0xff);
  return out;
}

fs::path write_block_scene(const fs::path& dir, const std::string& file_name,
                           const std::function<std::string(std::string)>& edit) {
  const fs::path trajectory = dir / "trajectories" / "poke_block.csv";
  if (!fs::exists(trajectory))
    write_text(trajectory, read_text(source_dir() / "config/scenes/trajectories/poke_block.csv"));
  std::string text = read_text(source_dir() / "config/scenes/block_press.yaml");
  if (edit) text = edit(text);
  const fs::path scene = dir / file_name;
  write_text(scene, text);
  return scene;
}

std::vector<Case> all_cases() {
  std::vector<Case> all;
  for (auto&& part : {scene_cases(), mesh_cases(), volume_cases(), trajectory_cases(), recording_cases(),
                      calibration_cases(), command_line_cases()})
    all.insert(all.end(), part.begin(), part.end());
  // Names unique across kinds: Scene_Empty, Trajectory_Empty, CommandLine_NoCommand, ...
  for (Case& c : all) {
    std::string prefix;
    bool upper = true;
    for (char ch : c.kind) {
      if (ch == ' ') {
        upper = true;
        continue;
      }
      prefix += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(ch))) : ch;
      upper = false;
    }
    c.name = prefix + "_" + c.name;
  }
  return all;
}

}  // namespace fetouch::testing::hostile
