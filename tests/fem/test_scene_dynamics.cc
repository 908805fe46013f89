// A scene's inertia and damping effects become the solver's time stepping, or are refused by name.
#include <gtest/gtest.h>

#include "config/scene_loader.h"
#include "fem/tissue_model.h"

namespace fetouch::fem {
namespace {

config::Scene scene_with(const std::string& effects) {
  const std::string text = "name: s\nunits: SI\nmesh:\n  generate: {shape: box, size_m: [0.1, 0.1, 0.1], refinements: 0}\n"
                           "  element: p1\nmaterial: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.3, "
                           "density_kg_per_m3: 1100}\nsolver: {rate_hz: 25}\neffects:\n" + effects;
  return config::parse_scene(text, "test", ".").scene;
}

TEST(SceneDynamics, InertiaAndMassDampingMapToTheSolver) {
  EXPECT_FALSE(scene_dynamics(scene_with("  - gravity\n")).has_value());
  const auto d = scene_dynamics(scene_with("  - inertia: {integrator: newmark}\n  - damping: {mass_coefficient_per_s: 2}\n"));
  ASSERT_TRUE(d.has_value());
  EXPECT_TRUE(d->newmark);
  EXPECT_DOUBLE_EQ(d->time_step_s, 1.0 / 25);  // one step per solver frame
  EXPECT_DOUBLE_EQ(d->density_kg_per_m3, 1100);
  EXPECT_DOUBLE_EQ(d->rayleigh_mass_per_s, 2);
  EXPECT_FALSE(scene_dynamics(scene_with("  - inertia\n"))->newmark);  // backward Euler by default
  EXPECT_DOUBLE_EQ(scene_dynamics(scene_with("  - inertia\n  - damping: {stiffness_coefficient_s: 0.01}\n"))->rayleigh_stiffness_s,
                   0.01);
}

// HHT-alpha: Newmark's parameters from alpha (beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha).
TEST(SceneDynamics, HhtTakesNewmarksParametersFromItsAlpha) {
  const auto d = scene_dynamics(scene_with("  - inertia: {integrator: hht, hht_alpha: -0.3}\n"));
  ASSERT_TRUE(d.has_value());
  EXPECT_TRUE(d->newmark);
  EXPECT_DOUBLE_EQ(d->hht_alpha, -0.3);
  EXPECT_DOUBLE_EQ(d->beta, 1.3 * 1.3 / 4);
  EXPECT_DOUBLE_EQ(d->gamma, 0.8);
  EXPECT_DOUBLE_EQ(scene_dynamics(scene_with("  - inertia: {integrator: hht}\n"))->hht_alpha, -0.1);  // the documented default
}

}  // namespace
}  // namespace fetouch::fem
