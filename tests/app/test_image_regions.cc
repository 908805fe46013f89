// app::image_label_map against a volume built by hand: a covered box (intensity 5, with a
// one-voxel gap inside that closing fills) around a bright block (intensity 200), zero elsewhere.
// Label 2 is the block, label 1 the rest of the box, 0 outside: voxel counts equal the shapes'.
#include <gtest/gtest.h>

#include "app/mesh_pipeline.h"

namespace fetouch::app {
namespace {

TEST(ImageRegions, TheCoveredMediumSurroundsTheSegmentedBlock) {
  imaging::Volume<float> image;
  image.dimensions = {30, 30, 30};
  image.spacing_mm = {0.5, 0.5, 0.5};
  image.data.assign(30 * 30 * 30, 0.0f);
  const auto inside = [](int i, int lo, int hi) { return i >= lo && i < hi; };
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) {
        float v = 0;
        if (inside(i, 5, 25) && inside(j, 5, 25) && inside(k, 5, 25)) v = 5;      // the medium: 20^3
        if (inside(i, 10, 20) && inside(j, 10, 20) && inside(k, 8, 14)) v = 200;  // the block: 10 x 10 x 6
        if (i == 15 && j == 22 && k == 20) v = 0;                                 // a dark voxel in the medium
        image.data[image.index(i, j, k)] = v;
      }
  imaging::TissueSegmentation bright;
  bright.threshold = 100;
  bright.smoothing = imaging::TissueSegmentation::Smoothing::none;
  bright.closing = 1;
  float used = 0;
  const imaging::Volume<float> labels = image_label_map(image, bright, &used);
  EXPECT_FLOAT_EQ(used, 100);
  long counts[3] = {0, 0, 0};
  for (float l : labels.data) ++counts[static_cast<int>(l)];
  EXPECT_EQ(counts[2], 10 * 10 * 6);
  EXPECT_EQ(counts[1], 20 * 20 * 20 - 10 * 10 * 6);
  EXPECT_EQ(counts[0], 30 * 30 * 30 - 20 * 20 * 20);
  EXPECT_EQ(labels.data[labels.index(15, 22, 20)], 1.0f) << "the dark voxel inside the cover is medium";
  EXPECT_EQ(labels.data[labels.index(15, 15, 10)], 2.0f);
  EXPECT_EQ(labels.data[labels.index(2, 2, 2)], 0.0f);
}

}  // namespace
}  // namespace fetouch::app
