// The PLUS calibration reader (the Image-to-Probe transform of an XML configuration).
#include "imaging/reconstruction.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    fetouch::imaging::read_image_to_probe(fetouch::fuzz::as_file(data, size, ".xml"));
  } catch (const std::exception&) {
  }
  return 0;
}
