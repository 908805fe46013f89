// Volume headers written by hand in each format, read back with the values written.
#include <gtest/gtest.h>

#include <fstream>

#include "imaging/volume_info.h"

namespace fetouch::imaging {
namespace {

class VolumeInfoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("fetouch_volume_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::filesystem::path write(const std::string& name, const std::string& header, size_t bytes) {
    const auto path = dir_ / name;
    std::ofstream out(path, std::ios::binary);
    out << header << std::string(bytes, '\x07');
    return path;
  }

  std::filesystem::path dir_;
};

TEST_F(VolumeInfoTest, MetaImageHeader) {
  const auto path = write("v.mha",
                          "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\n"
                          "ElementSpacing = 0.5 0.25 2\nOffset = 10 20 30\n"
                          "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                          4 * 3 * 2);
  const VolumeInfo info = read_volume_info(path);
  EXPECT_EQ(info.format, "MetaImage");
  EXPECT_EQ(info.dimensions, (std::array<int, 3>{4, 3, 2}));
  EXPECT_EQ(info.spacing_mm, (std::array<double, 3>{0.5, 0.25, 2}));
  EXPECT_EQ(info.origin_mm, (std::array<double, 3>{10, 20, 30}));
  EXPECT_EQ(info.scalar_type, "unsigned char");
  EXPECT_EQ(info.components, 1);
  EXPECT_DOUBLE_EQ(info.voxel_count(), 24);
  EXPECT_DOUBLE_EQ(info.extent_mm()[2], 4.0);
}

TEST_F(VolumeInfoTest, NrrdHeader) {
  // VTK's NRRD reader takes a fastest axis of 9 samples or fewer for vector components, so the
  // first axis here is long enough to be read as space.
  const auto path = write("v.nrrd",
                          "NRRD0004\ntype: short\ndimension: 3\nsizes: 12 2 2\n"
                          "spacings: 0.3 0.3 0.6\nencoding: raw\nendian: little\n\n",
                          12 * 2 * 2 * 2);
  const VolumeInfo info = read_volume_info(path);
  EXPECT_EQ(info.format, "NRRD");
  EXPECT_EQ(info.dimensions, (std::array<int, 3>{12, 2, 2}));
  EXPECT_DOUBLE_EQ(info.spacing_mm[2], 0.6);
  EXPECT_EQ(info.scalar_type, "short");
}

TEST_F(VolumeInfoTest, BadFilesNameTheFile) {
  const auto garbage = write("garbage.mha", "this is not a header\n", 10);
  try {
    read_volume_info(garbage);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("garbage.mha"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_volume_info(dir_ / "missing.mha"), std::runtime_error);
  EXPECT_THROW(read_volume_info(write("v.png", "", 4)), std::runtime_error);
}

}  // namespace
}  // namespace fetouch::imaging
