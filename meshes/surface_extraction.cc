#include "meshes/surface_extraction.h"

#include <vtkAlgorithm.h>
#include <vtkCleanPolyData.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkImageGaussianSmooth.h>
#include <vtkImageResample.h>
#include <vtkMassProperties.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkQuadricDecimation.h>
#include <vtkWindowedSincPolyDataFilter.h>

#include <algorithm>
#include <cmath>

namespace fetouch::meshes {

vtkSmartPointer<vtkPolyData> smoothed_surface(vtkPolyData* surface, int iterations) {
  auto smooth = vtkSmartPointer<vtkWindowedSincPolyDataFilter>::New();
  smooth->SetInputData(surface);
  smooth->SetNumberOfIterations(iterations);
  smooth->SetPassBand(0.1);
  smooth->BoundarySmoothingOff();
  smooth->FeatureEdgeSmoothingOff();
  smooth->NonManifoldSmoothingOn();
  smooth->NormalizeCoordinatesOn();
  smooth->Update();
  return smooth->GetOutput();
}

vtkSmartPointer<vtkPolyData> blurred_level_set(vtkImageData* indicator, const std::array<double, 3>& sigma_voxels,
                                               const std::array<double, 3>& magnify, bool largest_only) {
  auto blur = vtkSmartPointer<vtkImageGaussianSmooth>::New();
  blur->SetInputData(indicator);
  blur->SetStandardDeviations(sigma_voxels.data());
  blur->SetRadiusFactors(2, 2, 2);
  vtkSmartPointer<vtkAlgorithm> field = blur;
  if (*std::min_element(magnify.begin(), magnify.end()) < 1) {
    auto coarse = vtkSmartPointer<vtkImageResample>::New();
    coarse->SetInputConnection(blur->GetOutputPort());
    for (int d = 0; d < 3; ++d) coarse->SetAxisMagnificationFactor(d, magnify[std::size_t(d)]);
    coarse->SetInterpolationModeToLinear();
    field = coarse;
  }
  auto contour = vtkSmartPointer<vtkFlyingEdges3D>::New();
  contour->SetInputConnection(field->GetOutputPort());
  contour->SetValue(0, 0.5);
  contour->ComputeNormalsOff();
  contour->ComputeGradientsOff();
  contour->ComputeScalarsOff();
  vtkSmartPointer<vtkAlgorithm> pieces = contour;
  if (largest_only) {
    auto largest = vtkSmartPointer<vtkPolyDataConnectivityFilter>::New();
    largest->SetInputConnection(contour->GetOutputPort());
    largest->SetExtractionModeToLargestRegion();
    pieces = largest;
  }
  auto clean = vtkSmartPointer<vtkCleanPolyData>::New();
  clean->SetInputConnection(pieces->GetOutputPort());
  clean->Update();
  return clean->GetOutput();
}

vtkSmartPointer<vtkPolyData> decimated_towards(vtkPolyData* surface, double triangle_mm, double fewest) {
  auto mass = vtkSmartPointer<vtkMassProperties>::New();
  mass->SetInputData(surface);
  mass->Update();
  const double wanted = std::max(fewest, mass->GetSurfaceArea() / (std::sqrt(3.0) / 4 * triangle_mm * triangle_mm));
  const double have = surface->GetNumberOfPolys();
  if (!(wanted < have)) return surface;
  auto decimate = vtkSmartPointer<vtkQuadricDecimation>::New();
  decimate->SetInputData(surface);
  decimate->SetTargetReduction(1 - wanted / have);
  decimate->VolumePreservationOn();
  decimate->Update();
  return smoothed_surface(decimate->GetOutput(), 10);
}

}  // namespace fetouch::meshes
