// The HDF5 recording reader, as `replay --trajectory FILE.h5` uses it.
#include "app/recording.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    fetouch::app::read_probe_trajectory(fetouch::fuzz::as_file(data, size, ".h5"), "tool", 0);
  } catch (const std::exception&) {
  }
  return 0;
}
