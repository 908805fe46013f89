// Filters and segmentation on volumes (imaging/phantom.h's Volume), in voxel units unless a name
// says mm:
//   - speckle reduction: Gaussian smoothing (separable, sigma in mm) and the 3 x 3 x 3 median;
//   - time-gain compensation: undoing the depth attenuation exp(-mu d) along -z beams;
//   - threshold: voxels within [low, high] -> mask;
//   - connected components (6-connectivity): the largest, the largest that does not touch the
//     volume's faces (an object floating in fluid), or the one holding a seed (region growing);
//   - morphology: closing by a ball (dilation then erosion) and filling enclosed holes (background
//     voxels not connected to the volume's faces).
// Masks are 0/1 volumes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "imaging/phantom.h"

namespace fetouch::imaging {

using Mask = Volume<std::uint8_t>;

Volume<float> gaussian_smooth(const Volume<float>& v, double sigma_mm);
Volume<float> median3(const Volume<float>& v);
Volume<float> compensate_depth(const Volume<float>& v, double attenuation_per_mm);
Mask threshold(const Volume<float>& v, float low, float high);
// The voxels of a label map whose value is one of `labels`.
Mask select_labels(const Volume<float>& labels_map, const std::vector<int>& labels);

enum class ComponentChoice { largest, largest_interior, containing_seed };
// Throws std::runtime_error when there is no such component (an empty segmentation), naming why.
Mask connected_component(const Mask& mask, ComponentChoice choice, std::array<int, 3> seed = {0, 0, 0});
Mask close(const Mask& mask, int radius);
// Dilation by a ball of `radius` voxels.
Mask dilate(const Mask& mask, int radius);
Mask fill_holes(const Mask& mask);

// The fetus of a phantom image (or a real fetal volume of the same look): smoothing, depth
// compensation, a threshold between fluid and tissue, the largest component floating in the fluid,
// closing and hole filling. A shadow (under the skull) can darken the far side of a bright shell below
// that threshold and leave it open: what a lower threshold's closed shell encloses is added.
struct FetusSegmentation {
  double smoothing_mm = 1.5;
  double attenuation_per_mm = 0.006;  // 0: no compensation
  float threshold = 45;      // between fluid and tissue: where the boundary lies
  float low_threshold = 20;  // through shadows: closes the skull, so the brain it encloses is found
  int closing_radius = 2;
};
Mask segment_fetus(const Volume<float>& image, const FetusSegmentation& settings);

// How a volume becomes the tissue mask that is meshed (`fetouch mesh`, a scene's mesh.volume):
//   - labels: the voxels of these labels of a label map, the largest piece, holes filled;
//   - fetus: segment_fetus above;
//   - otherwise: smoothing (Gaussian of smoothing_mm, or the 3 x 3 x 3 median, or none), a
//     threshold (a value in the image's units, or a percentile of the smoothed volume; default:
//     halfway between the 5th and 95th percentiles of the smoothed volume),
//     the largest connected region, closing by `closing` voxels and hole filling.
// Throws std::runtime_error for an empty segmentation.
struct TissueSegmentation {
  std::vector<int> labels;
  bool fetus = false;
  std::optional<float> threshold;
  std::optional<double> threshold_percentile;  // 0..100, of the smoothed volume
  enum class Smoothing { none, gaussian, median } smoothing = Smoothing::gaussian;
  double smoothing_mm = 1.0;
  int closing = 2;
};
// `threshold_used`, if given, receives the threshold applied (the intensity pipeline only).
Mask segment_tissue(const Volume<float>& volume, const TissueSegmentation& settings, float* threshold_used = nullptr);

// Dice coefficient 2|A n B| / (|A| + |B|) of two masks of the same dimensions.
double dice(const Mask& a, const Mask& b);

}  // namespace fetouch::imaging
