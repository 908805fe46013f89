#include "fem/cavity.h"

namespace fetouch::fem {

double CavityLaw::pressure(double volume, double reference_volume) const {
  if (gas) return initial_pressure_pa * reference_volume / volume;
  return initial_pressure_pa - bulk_modulus_pa * (volume - reference_volume) / reference_volume;
}

double CavityLaw::volume(double pressure, double reference_volume) const {
  if (gas) return initial_pressure_pa * reference_volume / pressure;
  return reference_volume * (1 - (pressure - initial_pressure_pa) / bulk_modulus_pa);
}

double CavityLaw::volume_derivative(double pressure, double reference_volume) const {
  if (gas) return -initial_pressure_pa * reference_volume / (pressure * pressure);
  return -reference_volume / bulk_modulus_pa;
}

namespace {

std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace

double CavityWall::volume(const double* u) const {
  double v = 0;
  for (const Triangle& t : triangles) {
    const auto x = t.deformed(u);
    const auto bc = cross(x[1], x[2]);
    v += x[0][0] * bc[0] + x[0][1] * bc[1] + x[0][2] * bc[2];
  }
  return v / 6;
}

void CavityWall::add_gradient(const double* u, double scale, double* g) const {
  // dV/da = (b x c)/6, dV/db = (c x a)/6, dV/dc = (a x b)/6.
  for (const Triangle& t : triangles) {
    const auto x = t.deformed(u);
    for (int v = 0; v < 3; ++v) {
      const auto d = cross(x[(v + 1) % 3], x[(v + 2) % 3]);
      for (int c = 0; c < 3; ++c) g[t.dofs[v][c]] += scale * d[c] / 6;
    }
  }
}

}  // namespace fetouch::fem
