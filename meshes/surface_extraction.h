// Surfaces from masks by VTK, as the volume mesher makes them (meshes/volume_mesher.cc) and the
// trainer draws label maps' regions (app/trainer/label_surfaces.cc): a 0/1 field blurred and cut at
// one half, smoothed without shrinking, decimated towards a triangle size.
#pragma once

#include <vtkSmartPointer.h>

#include <array>

class vtkImageData;
class vtkPolyData;

namespace fetouch::meshes {

// Windowed-sinc smoothing: a low-pass filter on the surface that, unlike Laplacian smoothing,
// does not shrink it.
vtkSmartPointer<vtkPolyData> smoothed_surface(vtkPolyData* surface, int iterations);

// The 0.5 level set of `indicator` (a 0/1 field, in its own coordinates) blurred by a Gaussian of
// `sigma_voxels` per axis (reaching two of them) and, where an axis's `magnify` is under 1,
// resampled linearly by it first; cleaned (shared points merged); with `largest_only` its largest
// connected piece only. Empty (no polygon) when nothing reaches one half.
vtkSmartPointer<vtkPolyData> blurred_level_set(vtkImageData* indicator, const std::array<double, 3>& sigma_voxels,
                                               const std::array<double, 3>& magnify, bool largest_only);

// `surface` decimated (quadric, volume kept) towards triangles of `triangle_mm`, at least `fewest`
// of them, and smoothed again over 10 iterations (decimation folds it here and there); `surface`
// itself when it has no more triangles than that.
vtkSmartPointer<vtkPolyData> decimated_towards(vtkPolyData* surface, double triangle_mm, double fewest);

}  // namespace fetouch::meshes
