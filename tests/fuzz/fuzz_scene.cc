// The scene loader: YAML text to a validated Scene, or diagnostics.
#include <filesystem>
#include <string>

#include "config/scene_loader.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    fetouch::config::parse_scene(text, "fuzz.yaml", std::filesystem::temp_directory_path());
  } catch (const std::exception&) {
  }
  return 0;
}
