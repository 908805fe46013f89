// The tracked-sweep reader (PLUS .igs.mha: a MetaImage with per-frame poses).
#include "imaging/reconstruction.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    fetouch::imaging::read_tracked_sweep(fetouch::fuzz::as_file(data, size, ".igs.mha"));
  } catch (const std::exception&) {
  }
  return 0;
}
