// The trainer's ultrasound reslice through the deformed tissue (app/trainer/deformed_slice.h)
// against an independent resampling with VTK: the deformed mesh as a vtkUnstructuredGrid carrying
// the displacement, probed at each pixel (vtkProbeFilter) to move the pixel back to the reference
// configuration, X = x - u, and the reference volume probed there (vtkProbeFilter on vtkImageData).
#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkProbeFilter.h>
#include <vtkUnstructuredGrid.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <thread>

#include "app/trainer/deformed_slice.h"
#include "app/trainer/ultrasound_imager.h"

namespace fetouch::app::trainer {
namespace {

// A 6 x 6 x 6 cm block of 6^3 cubes, each split in six tetrahedra, centred on the origin.
struct Block {
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<unsigned int, 4>> tetrahedra;
  std::vector<unsigned int> material;
};

Block block() {
  Block b;
  const int n = 6;
  const double h = 0.01;
  const auto id = [n](int i, int j, int k) { return static_cast<unsigned int>((k * (n + 1) + j) * (n + 1) + i); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) b.points.push_back({i * h - 0.03, j * h - 0.03, k * h - 0.03});
  static constexpr int kRing[6] = {1, 3, 2, 6, 4, 5};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        unsigned int v[8];
        for (int c = 0; c < 8; ++c) v[c] = id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        for (int r = 0; r < 6; ++r) {
          b.tetrahedra.push_back({v[0], v[kRing[r]], v[kRing[(r + 1) % 6]], v[7]});
          b.material.push_back(k < 3 ? 1 : 2);
        }
      }
  return b;
}

// A press from above: the top pushed down under a bump, the sides bulging; smooth and invertible.
std::array<double, 3> displacement(const std::array<double, 3>& X) {
  const double bump = std::exp(-(X[0] * X[0] + X[1] * X[1]) / (2 * 0.012 * 0.012));
  const double depth = (X[2] + 0.03) / 0.06;  // 0 at the bottom, 1 on top
  return {0.002 * X[0] / 0.03 * depth, 0.001 * std::sin(40 * X[1]) * depth, -0.008 * bump * depth * depth};
}

// A reference volume with structure everywhere: a smooth pattern sampled on 1 mm voxels.
ReferenceVolume volume() {
  ReferenceVolume v;
  v.dimensions = {81, 81, 81};
  v.spacing_m = {1e-3, 1e-3, 1e-3};
  v.origin_m = Eigen::Vector3d(-0.04, -0.04, -0.04);
  v.data.resize(81 * 81 * 81);
  for (int k = 0; k < 81; ++k)
    for (int j = 0; j < 81; ++j)
      for (int i = 0; i < 81; ++i) {
        const double x = -0.04 + 1e-3 * i, y = -0.04 + 1e-3 * j, z = -0.04 + 1e-3 * k;
        v.data[(std::size_t(k) * 81 + j) * 81 + i] = static_cast<float>(120 + 60 * std::sin(150 * x) * std::cos(110 * z) + 900 * y);
      }
  return v;
}

TEST(DeformedSlice, MatchesAnIndependentVtkResamplingThroughTheDeformedMesh) {
  const Block b = block();
  std::vector<float> u;
  for (const auto& X : b.points)
    for (double c : displacement(X)) u.push_back(static_cast<float>(c));
  const ReferenceVolume reference = volume();
  const SlicePlane plane = probe_plane(Eigen::Vector3d(0.004, 0.002, 0.03), Eigen::Vector3d(0, 0.2, 1),
                                       Eigen::Vector3d::UnitX(), 0.07, 0.07, 96, 96);
  DeformedSlicer slicer(b.points, b.tetrahedra, b.material);
  std::vector<std::uint8_t> image, rest_image;
  std::vector<float> X, rest_X;
  slicer.slice(u, plane, &reference, 1.0, image, X);
  slicer.slice({}, plane, &reference, 1.0, rest_image, rest_X);

  // VTK: the deformed mesh with u on its points, probed at the pixels.
  vtkNew<vtkPoints> points;
  vtkNew<vtkDoubleArray> field;
  field->SetNumberOfComponents(3);
  field->SetName("u");
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    points->InsertNextPoint(b.points[i][0] + u[3 * i], b.points[i][1] + u[3 * i + 1], b.points[i][2] + u[3 * i + 2]);
    field->InsertNextTuple3(u[3 * i], u[3 * i + 1], u[3 * i + 2]);
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->GetPointData()->AddArray(field);
  for (const auto& t : b.tetrahedra) {
    const vtkIdType ids[4] = {t[0], t[1], t[2], t[3]};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  vtkNew<vtkPoints> pixels;
  for (int j = 0; j < plane.rows; ++j)
    for (int i = 0; i < plane.columns; ++i) {
      const Eigen::Vector3d p = plane.pixel(i, j);
      pixels->InsertNextPoint(p.x(), p.y(), p.z());
    }
  vtkNew<vtkPolyData> at;
  at->SetPoints(pixels);
  vtkNew<vtkProbeFilter> probe;
  probe->SetInputData(at);
  probe->SetSourceData(grid);
  probe->ComputeToleranceOff();  // a pixel just outside a cell must not be extrapolated into it
  probe->SetTolerance(1e-9);
  probe->Update();
  vtkDataArray* probed_u = probe->GetOutput()->GetPointData()->GetArray("u");
  vtkDataArray* valid = probe->GetOutput()->GetPointData()->GetArray(probe->GetValidPointMaskArrayName());
  ASSERT_NE(probed_u, nullptr);
  ASSERT_NE(valid, nullptr);

  // The reference volume as vtkImageData, probed at X = x - u (inside) or x (outside).
  vtkNew<vtkImageData> image_data;
  image_data->SetDimensions(81, 81, 81);
  image_data->SetSpacing(1e-3, 1e-3, 1e-3);
  image_data->SetOrigin(-0.04, -0.04, -0.04);
  vtkNew<vtkFloatArray> values;
  values->SetName("v");
  values->SetNumberOfTuples(static_cast<vtkIdType>(reference.data.size()));
  for (std::size_t i = 0; i < reference.data.size(); ++i) values->SetValue(static_cast<vtkIdType>(i), reference.data[i]);
  image_data->GetPointData()->SetScalars(values);
  vtkNew<vtkPoints> moved_back;
  for (vtkIdType p = 0; p < pixels->GetNumberOfPoints(); ++p) {
    double x[3];
    pixels->GetPoint(p, x);
    if (valid->GetComponent(p, 0) != 0)
      for (int c = 0; c < 3; ++c) x[c] -= probed_u->GetComponent(p, c);
    moved_back->InsertNextPoint(x);
  }
  vtkNew<vtkPolyData> back;
  back->SetPoints(moved_back);
  vtkNew<vtkProbeFilter> sample;
  sample->SetInputData(back);
  sample->SetSourceData(image_data);
  sample->Update();
  vtkDataArray* expected = sample->GetOutput()->GetPointData()->GetArray("v");
  ASSERT_NE(expected, nullptr);

  long inside = 0, differs_from_rest = 0, apart = 0, disputed = 0;
  double worst_X = 0, worst_grey = 0;
  for (vtkIdType p = 0; p < pixels->GetNumberOfPoints(); ++p) {
    const bool covered = valid->GetComponent(p, 0) != 0;
    // Pixels on the block's very edge may fall either side in the two methods: skip them.
    const bool ours = !std::isnan(X[3 * p]);
    if (covered != ours) {
      ++disputed;
      continue;
    }
    if (covered) {
      ++inside;
      double x[3];
      moved_back->GetPoint(p, x);
      double off = 0;
      for (int c = 0; c < 3; ++c) off = std::max(off, std::abs(x[c] - X[3 * p + c]));
      worst_X = std::max(worst_X, off);
      apart += off > 1e-7;
    }
    const double want = std::clamp(expected->GetComponent(p, 0), 0.0, 255.0);
    worst_grey = std::max(worst_grey, std::abs(want - image[p]));
    differs_from_rest += std::abs(int(image[p]) - int(rest_image[p])) > 8;
  }
  // The plane cuts the block over about half the image, and the two methods agree on which pixels
  // the tissue covers but for a few on its edge (a pixel the slicer misses would count here).
  EXPECT_GT(inside, 96 * 96 / 4);
  EXPECT_LT(disputed, inside / 200);
  // X(x) agrees to 0.1 um but on pixels a hair from a face between two tetrahedra: VTK's cell search
  // may take the neighbour the pixel is just outside of (by ~1e-3 in barycentric terms) and
  // extrapolate there, which moves X by a few micrometres (a hundredth of a pixel).
  EXPECT_LT(apart, inside / 50) << "pixels whose X differs by more than 0.1 um";
  EXPECT_LT(worst_X, 1e-5);
  EXPECT_LE(worst_grey, 1.0) << "grey levels: the same trilinear sample, rounded to a byte";
  // The press shows: a good share of the tissue's pixels differ from the undeformed slice.
  EXPECT_GT(differs_from_rest, inside / 10);
}

TEST(DeformedSlice, WithoutAVolumeTheImageIsTheCrossSectionByRegion) {
  const Block b = block();
  DeformedSlicer slicer(b.points, b.tetrahedra, b.material);
  SlicePlane plane;  // x-z plane through the origin, 10 x 10 cm
  plane.lateral = Eigen::Vector3d::UnitX(), plane.up = Eigen::Vector3d::UnitZ();
  plane.columns = plane.rows = 100;
  std::vector<std::uint8_t> image;
  std::vector<float> X;
  slicer.slice({}, plane, nullptr, 1.0, image, X);
  // Pixel rows from the top: z = +5 cm (outside), +1.5 cm (region 2), -1.5 cm (region 1).
  const auto at = [&](double x, double z) {
    const int i = static_cast<int>((x / 0.1 + 0.5) * 100), j = static_cast<int>((0.5 - z / 0.1) * 100);
    return image[std::size_t(j) * 100 + i];
  };
  EXPECT_EQ(at(0, 0.045), 0);
  EXPECT_EQ(at(0.045, 0), 0);
  EXPECT_NE(at(0, 0.015), 0);
  EXPECT_NE(at(0, -0.015), 0);
  EXPECT_NE(at(0, 0.015), at(0, -0.015));
}

// The trainer's imager thread (app/trainer/ultrasound_imager.h) against the slicer called here: the
// same image, the frame and plane it was asked for, each finished image taken once, and a burst of
// requests ending with the newest.
std::vector<float> pressed(const Block& b, double scale) {
  std::vector<float> u;
  for (const auto& X : b.points)
    for (double c : displacement(X)) u.push_back(static_cast<float>(scale * c));
  return u;
}

bool wait_for(UltrasoundImager& imager, UltrasoundImage& image) {
  for (int i = 0; i < 2000; ++i) {
    if (imager.take(image)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

TEST(UltrasoundImager, MakesOnItsThreadTheImageTheSlicerMakes) {
  const Block b = block();
  const auto reference = std::make_shared<const ReferenceVolume>(volume());
  const SlicePlane plane = probe_plane(Eigen::Vector3d(0.004, 0.002, 0.03), Eigen::Vector3d(0, 0.2, 1),
                                       Eigen::Vector3d::UnitX(), 0.07, 0.07, 96, 96);
  const std::vector<float> u = pressed(b, 1.0);
  DeformedSlicer slicer(b.points, b.tetrahedra, b.material);
  std::vector<std::uint8_t> want;
  std::vector<float> want_X;
  slicer.slice(u, plane, reference.get(), 0.8, want, want_X);

  UltrasoundImager imager(b.points, b.tetrahedra, b.material, reference, 0.8);
  UltrasoundImage image;
  EXPECT_FALSE(imager.take(image)) << "nothing was asked for";
  imager.request(7, u, plane);
  ASSERT_TRUE(wait_for(imager, image));
  EXPECT_EQ(image.frame, 7);
  EXPECT_EQ(image.plane.centre, plane.centre);
  EXPECT_EQ(image.pixels, want);
  ASSERT_EQ(image.reference.size(), want_X.size());
  for (std::size_t i = 0; i < want_X.size(); ++i)
    ASSERT_TRUE(image.reference[i] == want_X[i] || (std::isnan(image.reference[i]) && std::isnan(want_X[i]))) << i;
  EXPECT_FALSE(imager.take(image)) << "an image is taken once";

  UltrasoundImage now;
  imager.make_now(8, u, plane, now);
  EXPECT_EQ(now.frame, 8);
  EXPECT_EQ(now.pixels, want);
}

TEST(UltrasoundImager, ABurstOfRequestsEndsWithTheNewest) {
  const Block b = block();
  const auto reference = std::make_shared<const ReferenceVolume>(volume());
  const SlicePlane plane = probe_plane(Eigen::Vector3d(0, 0, 0.03), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(),
                                       0.07, 0.07, 64, 64);
  UltrasoundImager imager(b.points, b.tetrahedra, b.material, reference, 1.0);
  for (int frame = 1; frame <= 40; ++frame) imager.request(frame, pressed(b, frame / 40.0), plane);
  UltrasoundImage image;
  long last = 0;
  while (last < 40) {
    ASSERT_TRUE(wait_for(imager, image)) << "the newest request was never made (last made: " << last << ")";
    EXPECT_GT(image.frame, last) << "images come newest last";
    last = image.frame;
  }
  DeformedSlicer slicer(b.points, b.tetrahedra, b.material);
  std::vector<std::uint8_t> want;
  std::vector<float> want_X;
  slicer.slice(pressed(b, 1.0), plane, reference.get(), 1.0, want, want_X);
  EXPECT_EQ(image.pixels, want) << "the newest image shows the newest displacement";
}

}  // namespace
}  // namespace fetouch::app::trainer
