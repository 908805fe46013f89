// The trainer's ultrasound view (docs/trainer.md): a B-mode image in the probe's plane, resliced from
// the reference volume *through the deformed tissue*. A pixel at x (scene frame, deformed) shows the
// reference volume at X(x), the material point the deformation carried there: the mesh's
// tetrahedra that the plane cuts are rasterised in their deformed places, and inside each the
// barycentric coordinates of x give X = sum_i lambda_i X_i, which is exact for linear elements (the
// map is affine per tetrahedron) and the linear interpolation of the inverse map for others. A pixel
// that no tetrahedron covers is outside the tissue, which does not move: it shows the volume at x.
// Without a volume the image is the mesh's cross-section, a grey level per region.
//
// No Qt, no VTK: plain arrays, so tests and the window share it.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace fetouch::app::trainer {

// The image plane: pixel (i, j) (column i, row j; row 0 on top) is centred at
//   centre + ((i + 0.5) / columns - 0.5) width lateral + (0.5 - (j + 0.5) / rows) height up.
struct SlicePlane {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d lateral = Eigen::Vector3d::UnitX(), up = Eigen::Vector3d::UnitZ();  // orthonormal
  double width_m = 0.1, height_m = 0.1;
  int columns = 256, rows = 256;
  Eigen::Vector3d pixel(int i, int j) const {
    return centre + ((i + 0.5) / columns - 0.5) * width_m * lateral + (0.5 - (j + 0.5) / rows) * height_m * up;
  }
};

// The plane through `point` containing the direction `normal`, its top row at the point and the
// image going `depth_m` into the tissue (against the normal); the lateral axis is `towards` with
// its part along the normal removed (the scene's x axis when that is too close to the normal).
SlicePlane probe_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Eigen::Vector3d& towards,
                       double width_m, double depth_m, int columns, int rows);

// A scalar volume in the scene frame (m): voxel (i, j, k) at origin + direction (i, j, k) * spacing
// (direction row-major, its columns the index axes), x fastest. Trilinear between voxel centres,
// `outside` beyond them.
struct ReferenceVolume {
  std::array<int, 3> dimensions{0, 0, 0};
  std::array<double, 3> spacing_m{1e-3, 1e-3, 1e-3};
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();
  std::vector<float> data;
  float outside = 0;
  float sample(const Eigen::Vector3d& x) const;
  bool empty() const { return data.empty(); }
};

class DeformedSlicer {
 public:
  // The reference mesh: points (m), tetrahedra (indices into points) and each one's region.
  DeformedSlicer(std::vector<std::array<double, 3>> points, std::vector<std::array<unsigned int, 4>> tetrahedra,
                 std::vector<unsigned int> material);

  // One image of `plane` for the displacement (3 per point, m). `reference` (3 per pixel, row by row)
  // receives X for each pixel the tissue covers and NaN elsewhere; `image` (one byte per pixel):
  // the volume at X (or at x outside the tissue), scaled by `gain` and clamped to 0..255, or the
  // cross-section's grey levels when `volume` is null. Allocates only when the plane's size changes.
  void slice(const std::vector<float>& displacement, const SlicePlane& plane, const ReferenceVolume* volume, double gain,
             std::vector<std::uint8_t>& image, std::vector<float>& reference);

  std::size_t points() const { return points_.size(); }

 private:
  std::vector<Eigen::Vector3d> points_, deformed_;
  std::vector<std::array<unsigned int, 4>> tetrahedra_;
  std::vector<unsigned int> material_;
  std::vector<int> covering_;  // per pixel: the region + 1 (0: outside)
};

}  // namespace fetouch::app::trainer
