// NIfTI-1 read from its 348-byte header (the field offsets and codes of the standard's nifti1.h).
#include "imaging/nifti_io.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fetouch::imaging {

namespace {

constexpr int kHeaderBytes = 348;

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string number(double x) {
  std::ostringstream text;
  text << x;
  return text.str();
}

// Reads plain or gzip-compressed bytes alike (zlib passes a file that is not gzip through as is).
class Bytes {
 public:
  explicit Bytes(const std::filesystem::path& path) : name_(path.string()), file_(gzopen(name_.c_str(), "rb"), &gzclose) {
    if (!file_) throw std::runtime_error(name_ + ": cannot be opened");
  }
  // Up to `count` bytes; fewer only at the end of the data.
  std::vector<char> read(double count) {
    std::vector<char> out;
    while (double(out.size()) < count) {
      const std::size_t chunk = static_cast<std::size_t>(std::min(count - double(out.size()), double(1 << 26)));
      const std::size_t at = out.size();
      out.resize(at + chunk);
      const int got = gzread(file_.get(), out.data() + at, static_cast<unsigned>(chunk));
      if (got < 0) {
        int code = 0;
        throw std::runtime_error(name_ + ": its compressed data is corrupt (" + gzerror(file_.get(), &code) + ")");
      }
      out.resize(at + static_cast<std::size_t>(got));
      if (static_cast<std::size_t>(got) < chunk) break;
    }
    return out;
  }
  bool skip(double count) { return read(count).size() == static_cast<std::size_t>(count); }

 private:
  std::string name_;
  std::unique_ptr<gzFile_s, int (*)(gzFile)> file_;
};

struct Header {
  bool swapped = false;
  std::int16_t dim[8]{};
  std::int16_t datatype = 0, bitpix = 0, qform_code = 0, sform_code = 0;
  float pixdim[8]{}, vox_offset = 0, scl_slope = 0, scl_inter = 0;
  float quatern[3]{}, qoffset[3]{}, srow[3][4]{};
  std::uint8_t xyzt_units = 0;
  std::string magic;
};

template <class T>
T field(const std::vector<char>& bytes, int offset, bool swapped) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, bytes.data() + offset, sizeof(T));
  if (swapped) std::reverse(raw, raw + sizeof(T));
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return value;
}

// The data type's size in bytes and name, or 0 for a type that is not one scalar per voxel.
std::pair<int, const char*> type_of(int datatype) {
  switch (datatype) {
    case 2: return {1, "unsigned char"};
    case 4: return {2, "short"};
    case 8: return {4, "int"};
    case 16: return {4, "float"};
    case 64: return {8, "double"};
    case 256: return {1, "signed char"};
    case 512: return {2, "unsigned short"};
    case 768: return {4, "unsigned int"};
    case 1024: return {8, "long long"};
    case 1280: return {8, "unsigned long long"};
    default: return {0, ""};
  }
}

// The file holding the header, and the one holding the voxels (the same, or the .img of a pair).
std::filesystem::path data_file(const std::filesystem::path& path, const Header& h) {
  if (h.magic == "n+1") return path;
  std::string stem = path.string();
  const std::string name = lower(stem);
  const std::size_t cut = name.size() >= 7 && name.compare(name.size() - 7, 7, ".hdr.gz") == 0 ? 7 : 4;
  stem.resize(stem.size() - cut);
  for (const char* e : {".img", ".img.gz", ".IMG"}) {
    std::error_code error;
    if (std::filesystem::is_regular_file(stem + e, error)) return stem + e;
  }
  throw std::runtime_error(path.string() + ": a NIfTI header of a pair (magic 'ni1') but no " +
                           std::filesystem::path(stem + ".img").filename().string() + " beside it");
}

Header read_header(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(name + ": not a regular file (a volume is a file or a folder of DICOM slices, not a FIFO or device)");
  Bytes in(path);
  const std::vector<char> b = in.read(kHeaderBytes);
  if (b.size() < kHeaderBytes)
    throw std::runtime_error(name + ": " + std::to_string(b.size()) + " bytes; a NIfTI-1 header has 348");
  Header h;
  const std::int32_t size = field<std::int32_t>(b, 0, false);
  if (size == 540 || size == 0x1c020000)
    throw std::runtime_error(name + ": a NIfTI-2 header (540 bytes); NIfTI-1 is read (convert with nibabel or dcm2niix's -1 option)");
  if (size != kHeaderBytes) {
    if (field<std::int32_t>(b, 0, true) != kHeaderBytes)
      throw std::runtime_error(name + ": sizeof_hdr is " + std::to_string(size) + "; a NIfTI-1 header says 348");
    h.swapped = true;
  }
  h.magic = std::string(b.data() + 344, strnlen(b.data() + 344, 4));
  if (h.magic != "n+1" && h.magic != "ni1")
    throw std::runtime_error(name + ": no NIfTI magic ('n+1' or 'ni1'); an Analyze 7.5 header has no orientation and is not read");
  for (int i = 0; i < 8; ++i) h.dim[i] = field<std::int16_t>(b, 40 + 2 * i, h.swapped);
  h.datatype = field<std::int16_t>(b, 70, h.swapped);
  h.bitpix = field<std::int16_t>(b, 72, h.swapped);
  for (int i = 0; i < 8; ++i) h.pixdim[i] = field<float>(b, 76 + 4 * i, h.swapped);
  h.vox_offset = field<float>(b, 108, h.swapped);
  h.scl_slope = field<float>(b, 112, h.swapped);
  h.scl_inter = field<float>(b, 116, h.swapped);
  h.xyzt_units = static_cast<std::uint8_t>(b[123]);
  h.qform_code = field<std::int16_t>(b, 252, h.swapped);
  h.sform_code = field<std::int16_t>(b, 254, h.swapped);
  for (int i = 0; i < 3; ++i) h.quatern[i] = field<float>(b, 256 + 4 * i, h.swapped);
  for (int i = 0; i < 3; ++i) h.qoffset[i] = field<float>(b, 268 + 4 * i, h.swapped);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) h.srow[r][c] = field<float>(b, 280 + 16 * r + 4 * c, h.swapped);

  if (h.dim[0] < 3 || h.dim[0] > 7)
    throw std::runtime_error(name + ": dim[0] is " + std::to_string(h.dim[0]) + "; a volume has 3 dimensions (up to 7 with time and more)");
  for (int i = 1; i <= h.dim[0]; ++i)
    if (h.dim[i] < 1)
      throw std::runtime_error(name + ": dim[" + std::to_string(i) + "] is " + std::to_string(h.dim[i]) + "; each size must be at least 1");
  const auto [bytes, type] = type_of(h.datatype);
  if (bytes == 0)
    throw std::runtime_error(name + ": datatype " + std::to_string(h.datatype) +
                             " is not one scalar per voxel (integers and floats are read; complex and RGB are not)");
  if (h.bitpix != 8 * bytes)
    throw std::runtime_error(name + ": bitpix " + std::to_string(h.bitpix) + " does not match datatype " +
                             std::to_string(h.datatype) + " (" + type + ", " + std::to_string(8 * bytes) + " bits)");
  if (!(h.vox_offset >= 0 && h.vox_offset <= 1e8) || (h.magic == "n+1" && h.vox_offset < 348))
    throw std::runtime_error(name + ": vox_offset " + number(h.vox_offset) + "; the voxels start after the 348-byte header");
  return h;
}

double unit_mm(const Header& h) {
  switch (h.xyzt_units & 7) {
    case 1: return 1000;  // metres
    case 3: return 1e-3;  // micrometres
    default: return 1;    // millimetres, or unknown (taken as millimetres, as every reader does)
  }
}

// The 3 x 4 voxel-to-RAS map (mm) the standard prescribes.
std::array<std::array<double, 4>, 3> voxel_to_ras(const std::string& name, const Header& h) {
  std::array<std::array<double, 4>, 3> m{};
  const double unit = unit_mm(h);
  for (int i = 1; i <= 3; ++i)
    if (h.sform_code <= 0 && !(std::isfinite(h.pixdim[i]) && std::abs(h.pixdim[i]) > 0))
      throw std::runtime_error(name + ": pixdim[" + std::to_string(i) + "] is " + number(h.pixdim[i]) + "; a voxel size must be positive");
  if (h.sform_code > 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        if (!std::isfinite(h.srow[r][c]))
          throw std::runtime_error(name + ": srow_" + "xyz"[r] + "[" + std::to_string(c) + "] is not a finite number");
        m[r][c] = h.srow[r][c] * unit;
      }
  } else if (h.qform_code > 0) {
    const double b = h.quatern[0], c = h.quatern[1], d = h.quatern[2];
    if (!std::isfinite(b) || !std::isfinite(c) || !std::isfinite(d) || b * b + c * c + d * d > 1 + 1e-5)
      throw std::runtime_error(name + ": quatern_b, c, d = " + number(b) + ", " + number(c) + ", " + number(d) +
                               "; a unit quaternion's b^2 + c^2 + d^2 is at most 1");
    const double a = std::sqrt(std::max(0.0, 1 - (b * b + c * c + d * d)));
    const double r[3][3] = {{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
                            {2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b)},
                            {2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b}};
    const double qfac = h.pixdim[0] < 0 ? -1 : 1;
    const double step[3] = {std::abs(h.pixdim[1]), std::abs(h.pixdim[2]), qfac * std::abs(h.pixdim[3])};
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) m[row][col] = r[row][col] * step[col] * unit;
      if (!std::isfinite(h.qoffset[row])) throw std::runtime_error(name + ": qoffset_" + "xyz"[row] + " is not a finite number");
      m[row][3] = h.qoffset[row] * unit;
    }
  } else {
    for (int i = 0; i < 3; ++i) m[i][i] = std::abs(h.pixdim[i + 1]) * unit;
  }
  return m;
}

VolumeInfo info_of(const std::filesystem::path& path, const Header& h) {
  const std::string name = path.string();
  VolumeInfo info;
  info.format = "NIfTI";
  info.components = 1;
  info.scalar_type = type_of(h.datatype).second;
  for (int i = 0; i < 3; ++i) info.dimensions[i] = h.dim[i + 1];
  auto m = voxel_to_ras(name, h);
  for (int c = 0; c < 4; ++c) m[0][c] = -m[0][c], m[1][c] = -m[1][c];  // RAS -> LPS
  for (int c = 0; c < 3; ++c) {
    const double length = std::sqrt(m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]);
    if (!(length > 0))
      throw std::runtime_error(name + ": the " + (h.sform_code > 0 ? "sform" : "qform") + " maps index axis " +
                               std::to_string(c) + " to nothing (a zero column)");
    info.spacing_mm[c] = length;
    for (int r = 0; r < 3; ++r) info.direction[3 * r + c] = m[r][c] / length;
  }
  for (int r = 0; r < 3; ++r) info.origin_mm[r] = m[r][3];
  return info;
}

}  // namespace

bool is_nifti_name(const std::filesystem::path& path) {
  const std::string name = lower(path.filename().string());
  for (const char* e : {".nii", ".nii.gz", ".hdr", ".hdr.gz"}) {
    const std::size_t n = std::strlen(e);
    if (name.size() > n && name.compare(name.size() - n, n, e) == 0) return true;
  }
  return false;
}

VolumeInfo read_nifti_info(const std::filesystem::path& path) { return info_of(path, read_header(path)); }

Volume<float> read_nifti(const std::filesystem::path& path) {
  const std::string name = path.string();
  const Header h = read_header(path);
  const VolumeInfo info = info_of(path, h);
  const int bytes = type_of(h.datatype).first;
  const double voxels = info.voxel_count();
  const std::filesystem::path source = data_file(path, h);
  Bytes in(source);
  const double offset = std::floor(h.vox_offset);
  if (!in.skip(offset))
    throw std::runtime_error(source.string() + ": ends before vox_offset " + number(h.vox_offset));
  const std::vector<char> data = in.read(voxels * bytes);
  if (double(data.size()) < voxels * bytes)
    throw std::runtime_error(source.string() + ": dim " + std::to_string(h.dim[1]) + " x " + std::to_string(h.dim[2]) + " x " +
                             std::to_string(h.dim[3]) + " of " + type_of(h.datatype).second + " needs " +
                             std::to_string(static_cast<long long>(voxels * bytes)) + " bytes after the header but the file holds " +
                             std::to_string(data.size()));
  const bool scaled = std::isfinite(h.scl_slope) && h.scl_slope != 0 && std::isfinite(h.scl_inter) &&
                      !(h.scl_slope == 1 && h.scl_inter == 0);
  Volume<float> v;
  v.dimensions = info.dimensions, v.spacing_mm = info.spacing_mm, v.origin_mm = info.origin_mm, v.direction = info.direction;
  v.data.resize(static_cast<std::size_t>(voxels));
  // Each value in the file's byte order, as the type says.
  const auto value = [&](std::size_t o) -> double {
    unsigned char raw[8];
    std::memcpy(raw, data.data() + o, static_cast<std::size_t>(bytes));
    if (h.swapped) std::reverse(raw, raw + bytes);
    switch (h.datatype) {
      case 2: return raw[0];
      case 256: return static_cast<std::int8_t>(raw[0]);
      case 4: { std::int16_t x; std::memcpy(&x, raw, 2); return x; }
      case 512: { std::uint16_t x; std::memcpy(&x, raw, 2); return x; }
      case 8: { std::int32_t x; std::memcpy(&x, raw, 4); return x; }
      case 768: { std::uint32_t x; std::memcpy(&x, raw, 4); return x; }
      case 16: { float x; std::memcpy(&x, raw, 4); return x; }
      case 64: { double x; std::memcpy(&x, raw, 8); return x; }
      case 1024: { std::int64_t x; std::memcpy(&x, raw, 8); return static_cast<double>(x); }
      default: { std::uint64_t x; std::memcpy(&x, raw, 8); return static_cast<double>(x); }
    }
  };
  for (std::size_t i = 0; i < v.data.size(); ++i) {
    double x = value(i * static_cast<std::size_t>(bytes));
    if (scaled) x = h.scl_slope * x + h.scl_inter;
    v.data[i] = static_cast<float>(x);
    if (!std::isfinite(v.data[i])) {
      const std::size_t nx = std::size_t(v.dimensions[0]), ny = std::size_t(v.dimensions[1]);
      throw std::runtime_error(name + ": voxel (" + std::to_string(i % nx) + ", " + std::to_string(i / nx % ny) + ", " +
                               std::to_string(i / (nx * ny)) + ") is " + (std::isnan(x) ? "NaN" : "infinite") +
                               "; an image's intensities are finite");
    }
  }
  return v;
}

}  // namespace fetouch::imaging
