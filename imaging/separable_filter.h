// One axis of a separable convolution on an x-fastest volume array, in place. At the faces either
// periodic (a statistically stationary field, for synthetic speckle) or renormalised over the
// kernel's part inside the volume (filtering an image, whose faces are not walls of zeros).
#pragma once

#include <array>
#include <vector>

namespace fetouch::imaging {

enum class Faces { periodic, renormalised };

void convolve_axis(std::vector<float>& data, const std::array<int, 3>& dimensions, int axis, const std::vector<double>& kernel,
                   Faces faces);

// A 1D Gaussian of standard deviation sigma (voxels), truncated at 3 sigma; normalised to unit sum.
std::vector<double> gaussian_kernel(double sigma);

}  // namespace fetouch::imaging
