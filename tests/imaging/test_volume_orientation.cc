// Orientation (direction cosines) through every volume format: written and read back, or written
// by hand (NRRD, MetaImage headers; a DICOM series encoded here byte by byte), and a marker voxel
// found where the geometry the file states puts it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "imaging/volume_info.h"
#include "imaging/volume_io.h"
#include "tests/support/brightest_voxel.h"

namespace fetouch::imaging {
namespace {

namespace fs = std::filesystem;

class VolumeOrientation : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("fetouch_orientation_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A rotation by `angle` about the axis (1, 1, 1) / sqrt 3 (Rodrigues), row-major.
std::array<double, 9> rotation(double angle) {
  const double k[3] = {1 / std::sqrt(3.0), 1 / std::sqrt(3.0), 1 / std::sqrt(3.0)};
  const double c = std::cos(angle), s = std::sin(angle);
  std::array<double, 9> r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      r[3 * i + j] = (i == j ? c : 0) + (1 - c) * k[i] * k[j];
      const int e = (3 + j - i) % 3;  // Levi-Civita: + when (i, j) is (0,1), (1,2), (2,0)
      if (i != j) r[3 * i + j] += (e == 1 ? -1 : 1) * s * k[3 - i - j];
    }
  return r;
}

using testing::brightest_voxel;

TEST(Rotation, IsOrthonormalWithDeterminantOne) {
  const auto r = rotation(0.7);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += r[3 * k + a] * r[3 * k + b];
      EXPECT_NEAR(d, a == b, 1e-15);
    }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6]);
  EXPECT_NEAR(det, 1, 1e-15);
}

TEST_F(VolumeOrientation, RoundTripsKeepTheDirection) {
  Volume<std::uint8_t> v;
  v.dimensions = {6, 5, 4};
  v.spacing_mm = {0.5, 0.75, 1.25};
  v.origin_mm = {10, -20, 30};
  v.direction = rotation(0.7);
  v.data.assign(6 * 5 * 4, 0);
  v.data[v.index(4, 1, 3)] = 200;
  for (const char* name : {"rotated.mha", "rotated.mhd", "rotated.vti"}) {
    write_volume(v, dir_ / name);
    const Volume<float> back = read_volume(dir_ / name);
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(back.direction[k], v.direction[k], 1e-12) << name;
    EXPECT_EQ(brightest_voxel(back), (std::array<int, 3>{4, 1, 3})) << name;
    // Its place in space: origin + R (i dx, j dy, k dz), computed here from the rotation.
    const double step[3] = {4 * 0.5, 1 * 0.75, 3 * 1.25};
    const auto p = back.position_mm(4, 1, 3);
    for (int r = 0; r < 3; ++r) {
      double expected = v.origin_mm[r];
      for (int c = 0; c < 3; ++c) expected += v.direction[3 * r + c] * step[c];
      EXPECT_NEAR(p[r], expected, 1e-9) << name;
    }
    const VolumeInfo info = read_volume_info(dir_ / name);
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(info.direction[k], v.direction[k], 1e-12) << name;
  }
}

TEST_F(VolumeOrientation, HandWrittenHeaders) {
  // NRRD: each axis' step in space; axis 0 along y (2 mm), axis 1 along -x (3 mm), axis 2 along z.
  {
    std::ofstream out(dir_ / "v.nrrd", std::ios::binary);
    out << "NRRD0004\n# a comment: with a colon\ntype: unsigned char\ndimension: 3\nspace: left-posterior-superior\n"
           "sizes: 10 3 4\nspace directions: (0,2,0) (-3,0,0) (0,0,1.5)\nspace origin: (1,2,3)\nencoding: raw\n\n"
        << std::string(120, '\0');
  }
  const VolumeInfo nrrd = read_volume_info(dir_ / "v.nrrd");
  EXPECT_EQ(nrrd.dimensions, (std::array<int, 3>{10, 3, 4}));
  EXPECT_EQ(nrrd.components, 1);
  EXPECT_EQ(nrrd.spacing_mm, (std::array<double, 3>{2, 3, 1.5}));
  EXPECT_EQ(nrrd.origin_mm, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(nrrd.direction, (std::array<double, 9>{0, -1, 0, 1, 0, 0, 0, 0, 1}));
  // MetaImage: the same axes as TransformMatrix (axis 0's direction first).
  {
    std::ofstream out(dir_ / "v.mha", std::ios::binary);
    out << "ObjectType = Image\nNDims = 3\nBinaryData = True\nCompressedData = False\n"
           "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 1 2 3\nElementSpacing = 2 3 1.5\nDimSize = 2 3 4\n"
           "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
        << std::string(24, '\0');
  }
  const Volume<float> mha = read_volume(dir_ / "v.mha");
  EXPECT_EQ(mha.direction, (std::array<double, 9>{0, -1, 0, 1, 0, 0, 0, 0, 1}));
  EXPECT_EQ(mha.position_mm(1, 1, 0), (std::array<double, 3>{1 - 3, 2 + 2, 3}));
  // A malformed matrix is an error naming the key.
  {
    std::ofstream out(dir_ / "bad.mha", std::ios::binary);
    out << "ObjectType = Image\nNDims = 3\nTransformMatrix = 1 0 0 0 1\nDimSize = 2 3 4\n"
           "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
        << std::string(24, '\0');
  }
  try {
    read_volume(dir_ / "bad.mha");
    FAIL() << "a 5-number TransformMatrix was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("TransformMatrix"), std::string::npos) << e.what();
  }
}

// --- A DICOM series, encoded by hand: explicit VR little endian, one file per slice. ---

void element(std::string& out, std::uint16_t group, std::uint16_t tag, const char* vr, std::string value) {
  const bool long_form = std::string(vr) == "OB" || std::string(vr) == "OW";
  if (value.size() % 2) value += std::string(vr) == "UI" ? '\0' : ' ';
  const auto u16 = [&](std::uint16_t x) { out += char(x & 0xff), out += char(x >> 8); };
  const auto u32 = [&](std::uint32_t x) { u16(x & 0xffff), u16(x >> 16); };
  u16(group), u16(tag);
  out += vr;
  if (long_form) {
    u16(0), u32(static_cast<std::uint32_t>(value.size()));
  } else {
    u16(static_cast<std::uint16_t>(value.size()));
  }
  out += value;
}

std::string us(std::uint16_t x) { return std::string{char(x & 0xff), char(x >> 8)}; }

void write_dicom_slice(const fs::path& path, int slice, int rows, int columns, const std::string& position,
                       const std::string& orientation, const std::vector<std::uint16_t>& pixels) {
  std::string meta, data;
  element(meta, 0x0002, 0x0001, "OB", std::string("\0\1", 2));
  element(meta, 0x0002, 0x0002, "UI", "1.2.840.10008.5.1.4.1.1.7");
  element(meta, 0x0002, 0x0003, "UI", "1.2.3.4.5." + std::to_string(slice + 1));
  element(meta, 0x0002, 0x0010, "UI", "1.2.840.10008.1.2.1");
  element(meta, 0x0002, 0x0012, "UI", "1.2.3.4");
  std::string group_length;
  element(group_length, 0x0002, 0x0000, "UL", std::string{char(meta.size() & 0xff), char(meta.size() >> 8 & 0xff), 0, 0});
  // UL is a 4-byte value in a short-form element.
  element(data, 0x0008, 0x0016, "UI", "1.2.840.10008.5.1.4.1.1.7");
  element(data, 0x0008, 0x0018, "UI", "1.2.3.4.5." + std::to_string(slice + 1));
  element(data, 0x0008, 0x0060, "CS", "US");
  element(data, 0x0018, 0x0050, "DS", "2");
  element(data, 0x0018, 0x0088, "DS", "2");
  element(data, 0x0020, 0x000d, "UI", "1.2.3.4.6");
  element(data, 0x0020, 0x000e, "UI", "1.2.3.4.7");
  element(data, 0x0020, 0x0013, "IS", std::to_string(slice + 1));
  element(data, 0x0020, 0x0032, "DS", position);
  element(data, 0x0020, 0x0037, "DS", orientation);
  element(data, 0x0028, 0x0002, "US", us(1));
  element(data, 0x0028, 0x0004, "CS", "MONOCHROME2");
  element(data, 0x0028, 0x0010, "US", us(static_cast<std::uint16_t>(rows)));
  element(data, 0x0028, 0x0011, "US", us(static_cast<std::uint16_t>(columns)));
  element(data, 0x0028, 0x0030, "DS", "0.5\\0.75");  // row spacing (between rows), column spacing
  element(data, 0x0028, 0x0100, "US", us(16));
  element(data, 0x0028, 0x0101, "US", us(16));
  element(data, 0x0028, 0x0102, "US", us(15));
  element(data, 0x0028, 0x0103, "US", us(0));
  std::string bytes;
  for (std::uint16_t p : pixels) bytes += us(p);
  element(data, 0x7fe0, 0x0010, "OW", bytes);
  std::ofstream out(path, std::ios::binary);
  out << std::string(128, '\0') << "DICM" << group_length << meta << data;
}

TEST_F(VolumeOrientation, DicomSeriesLandsWhereItsHeadersSay) {
  // Three slices of 5 rows x 4 columns; rows run along +y, columns down along -z (a sagittal
  // image), slices step 2 mm along the normal row x column = (-1, 0, 0)... as the positions say.
  const int rows = 5, columns = 4;
  const std::string orientation = "0\\1\\0\\0\\0\\-1";
  const double row_dir[3] = {0, 1, 0}, column_dir[3] = {0, 0, -1};
  const double first[3] = {40, -10, 60}, normal[3] = {-1, 0, 0};  // row x column
  const fs::path series = dir_ / "series";
  fs::create_directories(series);
  const int marker_row = 1, marker_column = 3, marker_slice = 2;
  for (int s = 0; s < 3; ++s) {
    std::vector<std::uint16_t> pixels(rows * columns, 10);
    if (s == marker_slice) pixels[marker_row * columns + marker_column] = 1000;
    char position[64];
    std::snprintf(position, sizeof position, "%g\\%g\\%g", first[0] + 2 * s * normal[0], first[1] + 2 * s * normal[1],
                  first[2] + 2 * s * normal[2]);
    write_dicom_slice(series / ("slice" + std::to_string(s) + ".dcm"), s, rows, columns, position, orientation, pixels);
  }
  const Volume<float> v = read_volume(series);
  ASSERT_EQ(v.dimensions, (std::array<int, 3>{columns, rows, 3}));
  const auto at = brightest_voxel(v);
  const auto p = v.position_mm(at[0], at[1], at[2]);
  // Pixel (row r, column c) of the slice at P lies at P + c dc row_dir + r dr column_dir, with the
  // column spacing dc = 0.75 and the row spacing dr = 0.5 (PixelSpacing lists rows first).
  for (int d = 0; d < 3; ++d) {
    const double expected = first[d] + 2 * marker_slice * normal[d] + marker_column * 0.75 * row_dir[d] +
                            marker_row * 0.5 * column_dir[d];
    EXPECT_NEAR(p[d], expected, 1e-4) << "axis " << d << ", marker at voxel " << at[0] << " " << at[1] << " " << at[2];
  }
  const VolumeInfo info = read_volume_info(series);
  EXPECT_EQ(info.format, "DICOM series");
}

TEST_F(VolumeOrientation, EmptyFolderAndUnevenSlicesAreRefused) {
  fs::create_directories(dir_ / "empty");
  EXPECT_THROW(read_volume(dir_ / "empty"), std::runtime_error);
  // Slices at z = 0, 1 and 5: not one evenly spaced series.
  const fs::path series = dir_ / "uneven";
  fs::create_directories(series);
  int s = 0;
  for (const char* z : {"0", "1", "5"}) {
    write_dicom_slice(series / ("s" + std::to_string(s) + ".dcm"), s, 2, 2, std::string("0\\0\\") + z,
                      "1\\0\\0\\0\\1\\0", std::vector<std::uint16_t>(4, 1));
    ++s;
  }
  try {
    read_volume(series);
    FAIL() << "an uneven series was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("uneven"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fetouch::imaging

namespace fetouch::imaging {
namespace {

// Every kind of broken volume file gives an error that names the file (and what is wrong), never
// a volume of garbage.
TEST_F(VolumeOrientation, BrokenFilesAreRefusedByName) {
  Volume<std::uint8_t> v;
  v.dimensions = {20, 20, 20};
  v.data.resize(8000);
  for (std::size_t i = 0; i < v.data.size(); ++i) v.data[i] = static_cast<std::uint8_t>(i * 7919 % 251);
  write_volume(v, dir_ / "whole.mha");
  const std::string whole = read_file(dir_ / "whole.mha");
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir_ / name, std::ios::binary) << bytes;
    return dir_ / name;
  };
  const auto refused = [&](const fs::path& path, const std::string& why) {
    try {
      const Volume<float> back = read_volume(path);
      ADD_FAILURE() << path << " was read (" << back.data.size() << " voxels); expected: " << why;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  // Compressed data cut in half.
  refused(write("cut.mha", whole.substr(0, whole.size() / 2)), "");
  // Header fields that are wrong.
  const std::string body = std::string(8000, '\x01');
  refused(write("type.mha", "ObjectType = Image\nNDims = 3\nDimSize = 20 20 20\nElementType = MET_FOO\nElementDataFile = LOCAL\n" + body),
          "ElementType");
  refused(write("nodims.mha", "ObjectType = Image\nNDims = 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + body),
          "DimSize");
  // Dimensions the data does not fill: inline and in a separate raw file; a raw file missing.
  refused(write("big.mha", "ObjectType = Image\nNDims = 3\nDimSize = 20 20 21\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + body),
          "8400");
  write("short.raw", std::string(4000, '\x01'));
  refused(write("short.mhd", "ObjectType = Image\nNDims = 3\nDimSize = 20 20 20\nElementType = MET_UCHAR\nElementDataFile = short.raw\n"),
          "4000");
  refused(write("noraw.mhd", "ObjectType = Image\nNDims = 3\nDimSize = 20 20 20\nElementType = MET_UCHAR\nElementDataFile = none.raw\n"),
          "missing");
  refused(write("short.nrrd", "NRRD0004\ntype: unsigned char\ndimension: 3\nsizes: 20 20 20\nencoding: raw\n\n" + std::string(4000, '\x01')),
          "");
  refused(write("empty.vti", ""), "");
  refused(dir_ / "absent.mha", "no such file");
  refused(write("volume.png", "\x89PNG"), "unknown volume format");
}

// NRRD headers that VTK's reader would read otherwise than they look (it crashed on each; found by
// fuzz_volume) are refused, with the line; the same fields written as NRRD writes them read back.
TEST_F(VolumeOrientation, NrrdHeadersThatVtkWouldMisreadAreRefused) {
  std::string data(12 * 8 * 8, '\0');
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<char>(i % 13);
  const auto write = [&](const std::string& name, const std::string& header) {
    std::ofstream(dir_ / name, std::ios::binary) << header << data;
    return dir_ / name;
  };
  const auto refused = [&](const fs::path& path, const std::string& why) {
    try {
      read_volume(path);
      ADD_FAILURE() << path << " was read; expected: " << why;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  const std::string magic = "NRRD0004\ntype: uchar\n";
  const Volume<float> good = read_volume(write("good.nrrd", magic + "dimension: 3\nsizes: 12 8 8\nencoding: raw\n\n"));
  ASSERT_EQ(good.dimensions, (std::array<int, 3>{12, 8, 8}));
  for (std::size_t i = 0; i < data.size(); ++i) ASSERT_EQ(good.data[i], float(i % 13)) << i;
  refused(write("late.nrrd", magic + "sizes: 12 8 8\ndimension: 3\nencoding: raw\n\n"), ":3: 'sizes' comes before 'dimension'");
  refused(write("space.nrrd", magic + "dimension: 3\nspace dimension: 2\nsizes: 12 8 8\nencoding: raw\n\n"),
          ":4: space dimension: 2");
  refused(write("indented.nrrd", magic + "dimension: 3\n sizes: 12 8 8\nencoding: raw\n\n"), ":4: ' sizes: 12 8 8'");
  refused(write("spaced.nrrd", magic + "dimension: 3\nsizes : 12 8 8\nencoding: raw\n\n"), ":4: 'sizes : 12 8 8'");
  refused(write("hex.nrrd", magic + "dimension: 3\nsizes: 0xC 8 8\nencoding: raw\n\n"), "sizes = 0xC 8 8");
  // VTK's reader takes a first axis of 9 samples or fewer for the components of vectors.
  refused(write("short_axis.nrrd", magic + "dimension: 3\nsizes: 8 12 8\nencoding: raw\n\n"), "first axis of 8 samples");
  // A line of blanks does not end the header for VTK (it would read fields on into the data).
  refused(write("blank.nrrd", magic + "dimension: 3\nsizes: 12 8 8\nencoding: raw\n  \n\n"), ":6: '  '");
}

}  // namespace
}  // namespace fetouch::imaging
