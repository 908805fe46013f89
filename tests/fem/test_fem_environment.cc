// The tissue solver behind the haptic seam: the 3D haptic loop (PI local model, FOH, scheduled
// gains) pressing a probe into a neo-Hookean block through FemEnvironment settles where the finite
// element equilibrium says it must: the surface under the probe reaches the device (PI leaves no
// proxy offset) and the rendered force is the force that indents the tissue that far, checked by an
// independent static solve.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <cmath>
#include <cstdio>

#include "fem/fem_environment.h"
#include "fem/material.h"
#include "haptics/haptic_loop.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

std::unique_ptr<QuasiStaticSolver> pressed_block(dealii::Triangulation<3>& tria, const Material& material) {
  dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, {5, 4, 2}, Point<3>(0, 0, 0),
                                                                   Point<3>(0.1, 0.08, 0.05));
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary()) cell->face(f)->set_boundary_id(std::abs(cell->face(f)->center()[2]) < 1e-12 ? 4 : 1);
  auto solver = std::make_unique<QuasiStaticSolver>(tria, material, 2);
  solver->prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  solver->add_contact_patch(Point<3>(0.05, 0.04, 0.05), 0.01);
  return solver;
}

TEST(FemEnvironment, HapticLoopSettlesOnTheFiniteElementEquilibrium) {
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  dealii::Triangulation<3> tria;
  FemEnvironment environment(pressed_block(tria, material), NewtonSettings{});

  haptics::HapticLoopSettings settings;
  settings.local_model = haptics::LocalModelKind::pi;
  settings.hold = haptics::HoldKind::foh;
  haptics::HapticLoop loop(settings, haptics::initial_update(environment));
  haptics::LockstepSession session(loop, environment);
  const double depth = 0.002;  // 2 mm into the tissue
  const std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0.05, 0.04, 0.05 - depth)};
  double force = 0, penetration = 1;
  int frames_failed = 0;
  for (int k = 0; k < 50 * 50; ++k) {
    const auto& out = session.tick(device);
    force = out[0].normal_force, penetration = out[0].penetration;
    if (loop.decimated() && !loop.newest().update.status.converged) ++frames_failed;
    ASSERT_TRUE(out[0].force.allFinite());
  }
  const auto& frame = loop.newest().update.frames[0];
  std::printf("after 2.5 s: force %.6f N, penetration %.3g m, surface z %.6f m, normal (%.3f, %.3f, %.3f), Kh %.1f N/m\n",
              force, penetration, frame.point.z(), frame.normal.x(), frame.normal.y(), frame.normal.z(),
              loop.gains().proportional);
  EXPECT_EQ(frames_failed, 0);
  EXPECT_GT(force, 0.05);
  // PI leaves no proxy offset: the held surface passes through the device point along its normal
  // (the patch also slides a little sideways and tilts, so this is not a statement about z alone).
  EXPECT_LT(std::abs(penetration), 1e-9);
  EXPECT_LT(std::abs((frame.point - device[0]).dot(frame.normal)), 1e-9);
  EXPECT_NEAR(frame.point.z(), 0.05 - depth, 0.01 * depth);
  EXPECT_GT(frame.normal.z(), 0.99);  // the top stays nearly flat under the probe

  // Independently: a static solve with the force the loop sent the tissue puts the patch on the
  // device along the normal, to 1e-6 of the depth.
  dealii::Triangulation<3> tria2;
  auto check = pressed_block(tria2, material);
  Tensor<1, 3> f;
  for (int d = 0; d < 3; ++d) f[d] = loop.samples()[0].force(d);
  check->set_patch_force(0, f);
  NewtonSettings tight;
  tight.relative_tolerance = 1e-12;
  ASSERT_TRUE(check->solve(tight).converged);
  const Tensor<1, 3> u = check->patch_displacement(0);
  const Eigen::Vector3d surface(0.05 + u[0], 0.04 + u[1], 0.05 + u[2]);
  EXPECT_LT(std::abs((surface - device[0]).dot(frame.normal)), 1e-6 * depth);
}

}  // namespace
}  // namespace fetouch::fem
