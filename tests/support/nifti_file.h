// A NIfTI-1 file written byte by byte from the field offsets of the standard's nifti1.h (not by
// the reader under test): the tests set the fields, the voxels, and whether it is gzip-compressed.
#pragma once

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fetouch::testing {

struct NiftiFields {
  std::int16_t dim[8] = {3, 1, 1, 1, 1, 1, 1, 1};
  std::int16_t datatype = 2, bitpix = 8;  // unsigned char
  float pixdim[8] = {1, 1, 1, 1, 1, 1, 1, 1};
  float scl_slope = 0, scl_inter = 0;
  std::uint8_t xyzt_units = 2;  // millimetres
  std::int16_t qform_code = 0, sform_code = 0;
  float quatern_b = 0, quatern_c = 0, quatern_d = 0, qoffset[3] = {0, 0, 0};
  float srow[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  std::string magic = "n+1";
};

// Header (348 bytes), 4 bytes of extension flags, then `voxels` (already in the datatype's bytes).
inline std::string nifti_bytes(const NiftiFields& f, const std::string& voxels) {
  std::string b(352, '\0');
  const auto put = [&](int at, const void* value, std::size_t n) { std::memcpy(&b[std::size_t(at)], value, n); };
  const std::int32_t size = 348;
  put(0, &size, 4);
  put(40, f.dim, 16);
  put(70, &f.datatype, 2);
  put(72, &f.bitpix, 2);
  put(76, f.pixdim, 32);
  const float offset = 352;
  put(108, &offset, 4);
  put(112, &f.scl_slope, 4);
  put(116, &f.scl_inter, 4);
  b[123] = static_cast<char>(f.xyzt_units);
  put(252, &f.qform_code, 2);
  put(254, &f.sform_code, 2);
  put(256, &f.quatern_b, 4);
  put(260, &f.quatern_c, 4);
  put(264, &f.quatern_d, 4);
  put(268, f.qoffset, 12);
  put(280, f.srow, 48);
  std::memcpy(&b[344], f.magic.c_str(), std::min<std::size_t>(4, f.magic.size() + 1));
  return b + voxels;
}

inline void write_nifti(const std::filesystem::path& path, const std::string& bytes, bool gzip) {
  if (gzip) {
    gzFile out = gzopen(path.string().c_str(), "wb");
    if (!out || gzwrite(out, bytes.data(), static_cast<unsigned>(bytes.size())) != static_cast<int>(bytes.size()))
      throw std::runtime_error("cannot write " + path.string());
    gzclose(out);
  } else {
    std::ofstream(path, std::ios::binary) << bytes;
  }
}

}  // namespace fetouch::testing
