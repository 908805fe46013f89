// The volume readers: MetaImage (.mha), NRRD (.nrrd) and VTK image data (.vti); the first byte picks.
#include "imaging/volume_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const char* const kFormats[] = {".mha", ".nrrd", ".vti"};
  const char* format = kFormats[fetouch::fuzz::pick(data, size, 3)];
  try {
    fetouch::imaging::read_volume(fetouch::fuzz::as_file(data, size, format));
  } catch (const std::exception&) {
  }
  return 0;
}
