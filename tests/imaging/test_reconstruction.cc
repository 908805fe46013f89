// Reconstruction of the shared spine-phantom sweep (../shared/data/ultrasound, PLUS test data) with
// its calibration, against the volume PLUS reconstructed from the same sweep: the same extent within
// one voxel and a normalised cross-correlation of at least 0.9 over the voxels both fill.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "imaging/reconstruction.h"
#include "imaging/volume_io.h"
#include "tests/support/test_paths.h"

namespace fetouch::imaging {
namespace {

const std::filesystem::path kData = std::filesystem::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound";

// NCC over the voxels of `a` whose centre falls in a voxel of `b` where both are non-zero.
double ncc(const Volume<std::uint8_t>& a, const Volume<float>& b, long& overlap) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  overlap = 0;
  for (int l = 0; l < a.dimensions[2]; ++l)
    for (int j = 0; j < a.dimensions[1]; ++j)
      for (int i = 0; i < a.dimensions[0]; ++i) {
        const auto x = a.position_mm(i, j, l);
        int g[3];
        bool in = true;
        for (int d = 0; d < 3; ++d) {
          g[d] = static_cast<int>(std::lround((x[d] - b.origin_mm[d]) / b.spacing_mm[d]));
          in = in && g[d] >= 0 && g[d] < b.dimensions[d];
        }
        if (!in) continue;
        const double va = a.data[a.index(i, j, l)], vb = b.data[b.index(g[0], g[1], g[2])];
        if (va == 0 || vb == 0) continue;
        sa += va, sb += vb, saa += va * va, sbb += vb * vb, sab += va * vb, ++overlap;
      }
  const double n = static_cast<double>(overlap);
  return (sab - sa * sb / n) / std::sqrt((saa - sa * sa / n) * (sbb - sb * sb / n));
}

TEST(Reconstruction, SpineSweepAgreesWithPlusReconstruction) {
  if (!std::filesystem::exists(kData / "spine_phantom_freehand_sweep.igs.mha"))
    GTEST_SKIP() << "the shared ultrasound data is not at " << kData.string();
  const TrackedSweep sweep = read_tracked_sweep(kData / "spine_phantom_freehand_sweep.igs.mha");
  ASSERT_EQ(sweep.poses.size(), 21u);
  const Matrix4 calibration = read_image_to_probe(kData / "spine_phantom_freehand_calibration.xml");
  ReconstructionSettings settings;  // 0.5 mm, linear, mean, holes filled: the calibration file's settings
  const Reconstruction ours = reconstruct(sweep, calibration, settings);
  const Volume<float> plus = read_volume(kData / "spine_phantom_freehand_reconstructed.mha");
  std::printf("ours: %d x %d x %d from (%.3f, %.3f, %.3f) mm, %d frames, %.1f %% filled; PLUS: %d x %d x %d from "
              "(%.3f, %.3f, %.3f) mm\n",
              ours.volume.dimensions[0], ours.volume.dimensions[1], ours.volume.dimensions[2], ours.volume.origin_mm[0],
              ours.volume.origin_mm[1], ours.volume.origin_mm[2], ours.frames_used, 100 * ours.filled_fraction,
              plus.dimensions[0], plus.dimensions[1], plus.dimensions[2], plus.origin_mm[0], plus.origin_mm[1],
              plus.origin_mm[2]);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(ours.volume.origin_mm[d], plus.origin_mm[d], plus.spacing_mm[d]) << "axis " << d;
    const double our_end = ours.volume.origin_mm[d] + (ours.volume.dimensions[d] - 1) * ours.volume.spacing_mm[d];
    const double plus_end = plus.origin_mm[d] + (plus.dimensions[d] - 1) * plus.spacing_mm[d];
    EXPECT_NEAR(our_end, plus_end, plus.spacing_mm[d]) << "axis " << d;
  }
  long overlap = 0;
  const double correlation = ncc(ours.volume, plus, overlap);
  std::printf("normalised cross-correlation %.4f over %ld voxels both fill\n", correlation, overlap);
  EXPECT_GE(correlation, 0.9);
  EXPECT_GT(overlap, 100000);
}

TEST(Reconstruction, MalformedInputsAreRefusedByName) {
  EXPECT_THROW(read_tracked_sweep("/nonexistent/sweep.igs.mha"), std::runtime_error);
  const auto bad = std::filesystem::temp_directory_path() / ("calibration_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(bad) << "<PlusConfiguration><Transform From=\"Image\" To=\"Probe\" Matrix=\"1 0 0\"/></PlusConfiguration>";
  try {
    read_image_to_probe(bad);
    ADD_FAILURE() << "a 3-number matrix was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos);
  }
  std::filesystem::remove(bad);
}

// Calibration files that crashed `reconstruct` (issue 17: a stack overflow in the pattern matcher
// on a very long or whitespace-only attribute) or that hold no usable matrix: each refused naming the
// file; a well-formed one with other transforms around it, single quotes and spread attributes read.
TEST(Reconstruction, CalibrationFilesAreParsedWithoutRecursion) {
  const auto file = std::filesystem::temp_directory_path() / ("calibration_parse_" + std::to_string(::getpid()) + ".xml");
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"<Transform From=\"Image\" To=\"Probe\" Matrix=\"" + std::string(2'000'000, '1') + "\"/>", "not 16 finite numbers"},
      {"<Transform From=\"Image\" To=\"Probe\" Matrix=\"" + std::string(2'000'000, ' ') + "\"/>", "not 16 finite numbers"},
      {"<Transform" + std::string(2'000'000, ' ') + "From=\"Image\"/>", "no <Transform"},
      {"<Transform From=\"Image\" To=\"Probe\" Matrix=\"" + identity + "", "malformed"},
      {"<Transform From=\"Image\" To=\"Probe\"/>", "has no Matrix"},
      {"<Transform From=\"Image\" To=\"Probe\" Matrix=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 nan\"/>", "not 16 finite"},
  };
  for (const auto& [text, expected] : refused) {
    std::ofstream(file) << "<PlusConfiguration>\n" << text << "\n</PlusConfiguration>";
    try {
      read_image_to_probe(file);
      ADD_FAILURE() << text.substr(0, 60) << ": accepted";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file.string()), std::string::npos) << what.substr(0, 200);
      EXPECT_NE(what.find(expected), std::string::npos) << what.substr(0, 200);
      EXPECT_LT(what.size(), 400u);  // the message quotes at most a little of the file
    }
  }
  std::ofstream(file) << "<PlusConfiguration>\n<TransformRepository>\n"
                      << "<Transform From=\"Probe\" To=\"Tracker\" Matrix=\"" << identity << "\"/>\n"
                      << "<Transform\n   To='Probe'  From = \"Image\"\n   Matrix='2 0 0 1  0 2 0 2  0 0 2 3  0 0 0 1' />\n"
                      << "</TransformRepository></PlusConfiguration>";
  const Matrix4 m = read_image_to_probe(file);
  EXPECT_EQ(m[0], 2);
  EXPECT_EQ(m[3], 1);
  EXPECT_EQ(m[11], 3);
  EXPECT_EQ(m[15], 1);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace fetouch::imaging
