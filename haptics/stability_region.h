// Stability regions: the spectral radius of the lifted loop (stability_analysis.h) over a grid of
// the local model's gains (Kh, N I) for a given tissue (K0, B0), and the stability volume: the
// same over several K0. For the P-family models the integral axis has one point, N I = 0.
#pragma once

#include <vector>

#include "haptics/stability_analysis.h"

namespace fetouch::haptics {

struct RegionGrid {
  double kh_min = 0, kh_max = 2;
  int kh_points = 101;
  double ni_min = 0, ni_max = 2;  // N I, ignored (one point at 0) without an integrator
  int ni_points = 101;
};

struct StabilityRegion {
  double k0 = 1, b0 = 0;
  std::vector<double> kh, ni;  // the grid's axes
  std::vector<double> radius;  // spectral radius at (kh[a], ni[b]): radius[a * ni.size() + b]

  double at(std::size_t a, std::size_t b) const { return radius[a * ni.size() + b]; }
  std::size_t stable_points() const;
};

// `base` gives the local model, hold, N and one contact's K0 and B0; its gains are ignored.
// `progress`, if set, is called with the fraction done.
StabilityRegion stability_region(const LoopParameters& base, const RegionGrid& grid,
                                 void (*progress)(double fraction, void* context) = nullptr,
                                 void* context = nullptr);

}  // namespace fetouch::haptics
