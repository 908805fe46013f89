// The tissue solver behind the haptic seam: the 3D haptic loop (PI local model, FOH, scheduled
// gains) pressing a probe into a neo-Hookean block through FemEnvironment settles where the finite
// element equilibrium says it must: the surface under the probe reaches the device (PI leaves no
// proxy offset) and the rendered force is the force that indents the tissue that far, checked by an
// independent static solve.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <algorithm>
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

// A patch moved to a point is the patch added there: the same kernel, so the same displacement
// under the same force. And the nearest boundary point: on the reference block, the foot of the
// perpendicular on the face below (or beside) a point outside.
TEST(QuasiStaticSolver, MovedPatchIsThePatchAddedThereAndNearestPointsAreFeet) {
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  dealii::Triangulation<3> tria_a, tria_b;
  auto a = pressed_block(tria_a, material);
  auto b = pressed_block(tria_b, material);
  const Point<3> there(0.062, 0.035, 0.05);
  a->move_contact_patch(0, there);
  b->add_contact_patch(there, 0.01);  // b's patch 1; its patch 0 stays unloaded at the centre
  Tensor<1, 3> f;
  f[2] = -0.2;
  a->set_patch_force(0, f);
  b->set_patch_force(1, f);
  ASSERT_TRUE(a->solve(NewtonSettings{}).converged);
  ASSERT_TRUE(b->solve(NewtonSettings{}).converged);
  EXPECT_EQ(a->patch_center(0).distance(there), 0);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(a->patch_displacement(0)[d], b->patch_displacement(1)[d], 1e-12) << d;
  EXPECT_LT(a->patch_displacement(0)[2], -1e-4);

  EXPECT_LT(a->boundary_point_nearest(Point<3>(0.03, 0.02, 0.07), false).distance(Point<3>(0.03, 0.02, 0.05)), 1e-12);
  EXPECT_LT(a->boundary_point_nearest(Point<3>(0.13, 0.02, 0.03), false).distance(Point<3>(0.1, 0.02, 0.03)), 1e-12);
  // On the pressed block, the point just above the deformed patch maps back to the patch's centre
  // (to within the linear faces' reach of the dimple).
  const Tensor<1, 3> u = a->patch_displacement(0);
  const Point<3> above = there + u + Point<3>(0, 0, 1e-4);
  EXPECT_LT(a->boundary_point_nearest(above).distance(there), 0.003);
}

// A probe sliding over the surface while pressing: the patch follows it (FemEnvironment moves it
// by the probe's offset in the tangent plane), and where the slide ends the force is the force of
// pressing there directly (frictionless, hyperelastic: the path does not matter) to a few percent.
TEST(FemEnvironment, PatchFollowsASlidingProbe) {
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  const double depth = 0.002;
  const auto settle = [&](std::vector<Eigen::Vector3d> (*path)(int), int ticks, FemEnvironment& environment) {
    haptics::HapticLoopSettings settings;
    haptics::HapticLoop loop(settings, haptics::initial_update(environment));
    haptics::LockstepSession session(loop, environment);
    double force = 0;
    for (int k = 0; k < ticks; ++k) force = session.tick(path(k))[0].normal_force;
    return force;
  };
  dealii::Triangulation<3> tria_slide, tria_there;
  FemEnvironment sliding(pressed_block(tria_slide, material), NewtonSettings{});
  // Press 2 mm at the centre over 0.5 s, slide 20 mm along x over 1 s, hold 1.5 s.
  static double z0;
  z0 = 0.05 - depth;
  const double slid = settle(
      [](int k) {
        const double t = 1e-3 * k;
        const double x = 0.05 + 0.02 * std::clamp((t - 0.5) / 1.0, 0.0, 1.0);
        const double z = 0.05 - (0.05 - z0) * std::min(t / 0.5, 1.0);
        return std::vector<Eigen::Vector3d>{Eigen::Vector3d(x, 0.04, z)};
      },
      3000, sliding);
  const Point<3> centre = sliding.solver().patch_center(0);
  std::printf("after the slide: %ld patch moves, centre (%.4f, %.4f, %.4f), force %.4f N\n", sliding.patch_moves(),
              centre[0], centre[1], centre[2], slid);
  EXPECT_GE(sliding.patch_moves(), 4);  // 20 mm in steps of at least a quarter of the 10 mm radius
  EXPECT_LT(std::abs(centre[0] - 0.07), 0.25 * 0.01 + 1e-9);
  EXPECT_NEAR(centre[1], 0.04, 1e-3);

  // Pressing directly at the slide's end, with the patch where the slide left it.
  dealii::Triangulation<3> tria_direct;
  auto direct_solver = pressed_block(tria_direct, material);
  direct_solver->move_contact_patch(0, centre);
  FemEnvironment direct(std::move(direct_solver), NewtonSettings{});
  direct.set_follow_probes(false);
  const double there = settle(
      [](int k) {
        const double t = 1e-3 * k;
        const double z = 0.05 - (0.05 - z0) * std::min(t / 0.5, 1.0);
        return std::vector<Eigen::Vector3d>{Eigen::Vector3d(0.07, 0.04, z)};
      },
      3000, direct);
  std::printf("pressing there directly: %.4f N\n", there);
  EXPECT_GT(there, 0.02);
  EXPECT_NEAR(slid, there, 0.05 * there);
}

}  // namespace
}  // namespace fetouch::fem
