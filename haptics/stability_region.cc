#include "haptics/stability_region.h"

#include <stdexcept>

namespace fetouch::haptics {

namespace {

std::vector<double> axis(double low, double high, int points) {
  if (points < 1) throw std::invalid_argument("stability region: an axis needs at least one point");
  std::vector<double> values(points);
  for (int i = 0; i < points; ++i)
    values[i] = points == 1 ? low : low + (high - low) * static_cast<double>(i) / (points - 1);
  return values;
}

}  // namespace

std::size_t StabilityRegion::stable_points() const {
  std::size_t count = 0;
  for (double r : radius) count += r < 1.0;
  return count;
}

StabilityRegion stability_region(const LoopParameters& base, const RegionGrid& grid,
                                 void (*progress)(double, void*), void* context) {
  if (base.stiffness.rows() != 1)
    throw std::invalid_argument("stability region: one contact (scalar K0, B0) only");
  StabilityRegion region;
  region.k0 = base.stiffness(0, 0);
  region.b0 = base.damping(0, 0);
  region.kh = axis(grid.kh_min, grid.kh_max, grid.kh_points);
  region.ni = has_integrator(base.local_model) ? axis(grid.ni_min, grid.ni_max, grid.ni_points)
                                               : std::vector<double>{0.0};
  region.radius.reserve(region.kh.size() * region.ni.size());
  LoopParameters p = base;
  for (std::size_t a = 0; a < region.kh.size(); ++a) {
    for (double ni : region.ni) {
      p.gains = {region.kh[a], ni / p.ratio};
      region.radius.push_back(analyse(p).spectral_radius);
    }
    if (progress) progress(static_cast<double>(a + 1) / region.kh.size(), context);
  }
  return region;
}

}  // namespace fetouch::haptics
