// NIfTI-1 volumes written here byte by byte (tests/support/nifti_file.h) and read by
// imaging::read_volume: a marker voxel lands where the standard's voxel-to-world map puts it (sform;
// qform with a rotation and qfac = -1; pixdim alone), turned from NIfTI's RAS into Fetouch's LPS;
// values are scaled by scl_slope and scl_inter; metres become millimetres; .nii.gz reads as .nii;
// broken files are refused with the field and value that are wrong.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "imaging/volume_info.h"
#include "imaging/volume_io.h"
#include "tests/support/brightest_voxel.h"
#include "tests/support/nifti_file.h"

namespace fetouch::imaging {
namespace {

namespace fs = std::filesystem;
using testing::NiftiFields;

class Nifti : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("fetouch_nifti_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// A 6 x 5 x 4 unsigned char volume, 0 but for 200 at voxel (4, 1, 3).
NiftiFields small() {
  NiftiFields f;
  f.dim[1] = 6, f.dim[2] = 5, f.dim[3] = 4;
  return f;
}
std::string marker_voxels() {
  std::string v(6 * 5 * 4, '\0');
  v[(3 * 5 + 1) * 6 + 4] = static_cast<char>(200);
  return v;
}

// RAS (NIfTI's world) to LPS (Fetouch's): x and y change sign.
std::array<double, 3> lps(double r, double a, double s) { return {-r, -a, s}; }

void expect_at(const Volume<float>& v, std::array<int, 3> voxel, std::array<double, 3> expected, const char* what) {
  const auto p = v.position_mm(voxel[0], voxel[1], voxel[2]);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(p[d], expected[d], 1e-4) << what << ", axis " << d;
}

using testing::brightest_voxel;

TEST_F(Nifti, SformPlacesTheMarkerAndFlipsRasToLps) {
  NiftiFields f = small();
  f.sform_code = 1, f.qform_code = 1;  // the sform wins when both are set
  f.quatern_d = 1;                     // (the qform, a half turn, would put it elsewhere)
  // index -> RAS: spacings 0.75 (index axis 0 along anterior), 1.25 (axis 1 along superior), 0.5
  // (axis 2 along right).
  const float s[3][4] = {{0, 0, 0.5f, 10}, {0.75f, 0, 0, -20}, {0, 1.25f, 0, 30}};
  std::memcpy(f.srow, s, sizeof s);
  const fs::path file = dir_ / "sform.nii";
  testing::write_nifti(file, testing::nifti_bytes(f, marker_voxels()), false);
  const Volume<float> v = read_volume(file);
  ASSERT_EQ(v.dimensions, (std::array<int, 3>{6, 5, 4}));
  EXPECT_EQ(brightest_voxel(v), (std::array<int, 3>{4, 1, 3}));
  EXPECT_FLOAT_EQ(v.data[v.index(4, 1, 3)], 200);
  // RAS of (4, 1, 3): (0.5 * 3 + 10, 0.75 * 4 - 20, 1.25 * 1 + 30).
  expect_at(v, {4, 1, 3}, lps(11.5, -17, 31.25), "marker");
  expect_at(v, {0, 0, 0}, lps(10, -20, 30), "first voxel");
  EXPECT_NEAR(v.spacing_mm[0], 0.75, 1e-6);
  EXPECT_NEAR(v.spacing_mm[1], 1.25, 1e-6);
  EXPECT_NEAR(v.spacing_mm[2], 0.5, 1e-6);
  const VolumeInfo info = read_volume_info(file);
  EXPECT_EQ(info.format, "NIfTI");
  EXPECT_EQ(info.dimensions, v.dimensions);
}

TEST_F(Nifti, QformWithARotationAndReversedSlices) {
  NiftiFields f = small();
  f.qform_code = 1;
  // A quarter turn about superior: (b, c, d) = (0, 0, sin 45 deg), so R = [[0, -1, 0], [1, 0, 0],
  // [0, 0, 1]]; qfac = -1 (pixdim[0]) reverses the third index axis.
  f.quatern_d = static_cast<float>(std::sqrt(0.5));
  f.pixdim[0] = -1, f.pixdim[1] = 2, f.pixdim[2] = 3, f.pixdim[3] = 4;
  f.qoffset[0] = 5, f.qoffset[1] = 6, f.qoffset[2] = 7;
  const fs::path file = dir_ / "qform.nii.gz";
  testing::write_nifti(file, testing::nifti_bytes(f, marker_voxels()), true);
  const Volume<float> v = read_volume(file);
  EXPECT_EQ(brightest_voxel(v), (std::array<int, 3>{4, 1, 3}));
  // (i dx, j dy, -k dz) = (8, 3, -12); R of it = (-3, 8, -12); plus the offset.
  expect_at(v, {4, 1, 3}, lps(2, 14, -5), "marker");
  expect_at(v, {0, 0, 0}, lps(5, 6, 7), "first voxel");
}

TEST_F(Nifti, PixdimAloneScaledValuesAndMetres) {
  NiftiFields f = small();
  f.datatype = 4, f.bitpix = 16;  // signed short, as a CT's raw values
  f.scl_slope = 2, f.scl_inter = -1024;
  f.xyzt_units = 1;  // metres
  f.pixdim[1] = 0.001f, f.pixdim[2] = 0.002f, f.pixdim[3] = 0.003f;
  std::string voxels(6 * 5 * 4 * 2, '\0');
  for (std::size_t i = 0; i < 6 * 5 * 4; ++i) {
    const std::int16_t raw = static_cast<std::int16_t>(i == (3 * 5 + 1) * 6 + 4 ? 600 : 12);
    std::memcpy(&voxels[2 * i], &raw, 2);
  }
  const fs::path file = dir_ / "plain.nii";
  testing::write_nifti(file, testing::nifti_bytes(f, voxels), false);
  const Volume<float> v = read_volume(file);
  EXPECT_FLOAT_EQ(v.data[v.index(4, 1, 3)], 2 * 600 - 1024);
  EXPECT_FLOAT_EQ(v.data[0], 2 * 12 - 1024);
  EXPECT_NEAR(v.spacing_mm[0], 1, 1e-6);
  EXPECT_NEAR(v.spacing_mm[1], 2, 1e-6);
  EXPECT_NEAR(v.spacing_mm[2], 3, 1e-6);
  // Method 1 (no qform, no sform): index times pixdim, no orientation, in RAS like the others.
  expect_at(v, {4, 1, 3}, lps(4, 2, 9), "marker");
}

TEST_F(Nifti, BrokenFilesAreRefusedWithTheFieldThatIsWrong) {
  const auto refused = [&](const std::string& name, const std::string& bytes, bool gzip, const std::string& says) {
    const fs::path file = dir_ / name;
    testing::write_nifti(file, bytes, gzip);
    try {
      read_volume(file);
      ADD_FAILURE() << name << " was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << name << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << name << ": " << e.what();
    }
  };
  const std::string whole = testing::nifti_bytes(small(), marker_voxels());
  refused("short.nii", whole.substr(0, whole.size() - 7), false, "needs 120 bytes");
  refused("short.nii.gz", whole.substr(0, whole.size() - 7), true, "needs 120 bytes");
  refused("header.nii", whole.substr(0, 200), false, "348");
  NiftiFields f = small();
  f.magic = "abc";
  refused("magic.nii", testing::nifti_bytes(f, marker_voxels()), false, "magic");
  f = small();
  f.datatype = 128, f.bitpix = 24;  // RGB
  refused("rgb.nii", testing::nifti_bytes(f, marker_voxels()), false, "datatype 128");
  f = small();
  f.dim[2] = 0;
  refused("dim.nii", testing::nifti_bytes(f, marker_voxels()), false, "dim[2] is 0");
  f = small();
  f.sform_code = 1;
  f.srow[1][3] = std::nanf("");
  refused("nan.nii", testing::nifti_bytes(f, marker_voxels()), false, "srow_y[3]");
  f = small();
  f.dim[1] = 30000, f.dim[2] = 30000, f.dim[3] = 30000;
  refused("huge.nii", testing::nifti_bytes(f, marker_voxels()), false, "2^30");
  std::string nifti2 = whole;
  const std::int32_t size2 = 540;
  std::memcpy(&nifti2[0], &size2, 4);
  refused("two.nii", nifti2, false, "NIfTI-2");
}

}  // namespace
}  // namespace fetouch::imaging
