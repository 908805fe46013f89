// A probe smaller than the faces under it still has a patch (contact_patches.cc: a face larger than
// the radius is integrated on a subdivision of itself), and what it feels converges as the mesh
// is refined past the probe's size.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "config/scene_loader.h"
#include "fem/tissue_model.h"

namespace fetouch::fem {
namespace {

// A 1 cm x 1 cm x 5 mm slab of soft tissue on a table, P1: its top faces go from 5 mm (refinement
// 0) to 0.6 mm (refinement 3) across a probe of radius 1 mm.
std::unique_ptr<TissueModel> slab(int refinements) {
  const std::string text =
      "name: slab\nunits: SI\nmesh:\n  generate: {shape: box, size_m: [0.01, 0.01, 0.005], refinements: " +
      std::to_string(refinements) +
      "}\n  element: p1\nmaterial: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.45}\n"
      "effects: [contact]\nboundary:\n  - {name: table, type: fixed, select: {physical_group: zmin}}\n";
  return build_tissue_model(config::parse_scene(text, "slab.yaml", ".").scene);
}

// The normal stiffness a 1 mm probe at the top's centre feels: 1 / W_zz of the unloaded slab.
double felt_stiffness(int refinements, double radius) {
  const std::unique_ptr<TissueModel> model = slab(refinements);
  const int patch = model->solver->add_contact_patch(dealii::Point<3>(0.005, 0.005, 0.005), radius);
  EXPECT_TRUE(model->solver->solve(model->newton).converged);
  const dealii::FullMatrix<double> w = model->solver->compliance();
  EXPECT_NEAR(model->solver->patch_normal(patch)[2], 1, 1e-9);  // the top's normal, from the subdivided faces
  return 1 / w(2, 2);
}

TEST(SmallProbes, APatchOnFacesFiveTimesItsRadiusConvergesUnderRefinement) {
  std::vector<double> k;
  for (int r = 0; r <= 3; ++r) {
    k.push_back(felt_stiffness(r, 0.001));
    std::printf("refinement %d (top faces %.2f mm): felt stiffness %.2f N/m\n", r, 5.0 / (1 << r), k.back());
    EXPECT_TRUE(std::isfinite(k.back()) && k.back() > 0);
  }
  // A coarser mesh is stiffer (P1 is too stiff), and the changes shrink from level to level: the
  // sequence converges, at the rate the ratio of successive changes shows (under 1/2 here).
  for (std::size_t r = 1; r < k.size(); ++r) EXPECT_LT(k[r], k[r - 1]) << r;
  const double rate = (k[2] - k[3]) / (k[1] - k[2]);
  std::printf("ratio of successive changes: %.3f, %.3f\n", (k[1] - k[2]) / (k[0] - k[1]), rate);
  EXPECT_LT(rate, 0.5);
  // The Boussinesq half-space estimate for a patch of radius a on tissue of modulus E and ratio nu,
  // k ~ 2 E a / (1 - nu^2) (a rigid punch; the smooth kernel is softer), bounds the finest mesh from
  // above within a factor of two (the slab is thin, and its table stiffens it).
  const double punch = 2 * 5000 * 0.001 / (1 - 0.45 * 0.45);
  EXPECT_GT(k.back(), 0.5 * punch);
  EXPECT_LT(k.back(), 2 * punch);
}

// The force a small patch spreads is the probe's whole force: the table carries it back (global
// equilibrium), also where one face holds the whole patch.
TEST(SmallProbes, TheTableCarriesTheWholeForceOfAPatchOnOneFace) {
  const std::unique_ptr<TissueModel> model = slab(0);
  const int patch = model->solver->add_contact_patch(dealii::Point<3>(0.004, 0.006, 0.005), 0.001);
  dealii::Tensor<1, 3> force;
  force[0] = 0.002, force[2] = -0.01;
  model->solver->set_patch_force(patch, force);
  ASSERT_TRUE(model->solver->solve(model->newton).converged);
  const dealii::Tensor<1, 3> reaction = model->solver->boundary_force(model->region_ids.at("table"));
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(reaction[d], -force[d], 1e-8) << d;
}

}  // namespace
}  // namespace fetouch::fem
