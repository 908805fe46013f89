// The trajectory CSV reader (t, x, y, z rows) and its checks.
#include "haptics/devices.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    fetouch::haptics::read_trajectory_csv(fetouch::fuzz::as_file(data, size, ".csv"));
  } catch (const std::exception&) {
  }
  return 0;
}
