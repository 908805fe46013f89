// A tissue its supports do not hold is named as such, with the rigid motions left free, before any
// solve: rigid-body mechanics gives the answer for each support set.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <algorithm>
#include <string>
#include <vector>

#include "config/scene_loader.h"
#include "fem/material.h"
#include "fem/physical_problem.h"
#include "fem/quasi_static_solver.h"
#include "fem/tissue_model.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

std::vector<std::string> free_motions(QuasiStaticSolver& solver) {
  const std::vector<Discretisation::Piece> pieces = solver.pieces();
  EXPECT_EQ(pieces.size(), 1u);
  std::vector<std::string> motions = pieces.front().free_motions;
  std::sort(motions.begin(), motions.end());
  return motions;
}

TEST(HeldTissue, TheMotionsASupportLeavesFreeAreTheRigidBodyOnes) {
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_rectangle(tria, {2, 2, 1}, Point<3>(), Point<3>(0.1, 0.08, 0.05), true);
  const LinearElastic material(lame_lambda(5000, 0.3), lame_mu(5000, 0.3));
  {  // nothing: all six
    QuasiStaticSolver solver(tria, material, 1);
    EXPECT_EQ(free_motions(solver).size(), 6u);
  }
  {  // a frictionless table (u_z = 0 on the bottom): it slides and turns in its plane
    QuasiStaticSolver solver(tria, material, 1);
    solver.prescribe_displacement(4, {false, false, true}, Tensor<1, 3>());
    EXPECT_EQ(free_motions(solver),
              (std::vector<std::string>{"rotation about z", "translation along x", "translation along y"}));
  }
  {  // and a symmetry plane x = 0 (u_x = 0): it still slides along y
    QuasiStaticSolver solver(tria, material, 1);
    solver.prescribe_displacement(4, {false, false, true}, Tensor<1, 3>());
    solver.prescribe_displacement(0, {true, false, false}, Tensor<1, 3>());
    EXPECT_EQ(free_motions(solver), (std::vector<std::string>{"translation along y"}));
  }
  {  // the bottom fixed: held
    QuasiStaticSolver solver(tria, material, 1);
    solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
    EXPECT_TRUE(free_motions(solver).empty());
  }
  {  // P2 on the same: the edge dofs change nothing
    QuasiStaticSolver solver(tria, material, 2);
    solver.prescribe_displacement(4, {false, false, true}, Tensor<1, 3>());
    EXPECT_EQ(free_motions(solver).size(), 3u);
  }
}

TEST(HeldTissue, APieceApartIsFoundAndHeldOrNotOnItsOwn) {
  dealii::Triangulation<3> left, right, both;
  dealii::GridGenerator::subdivided_hyper_rectangle(left, {2, 2, 1}, Point<3>(), Point<3>(0.04, 0.04, 0.02));
  dealii::GridGenerator::subdivided_hyper_rectangle(right, {1, 1, 1}, Point<3>(0.06, 0, 0), Point<3>(0.08, 0.02, 0.02));
  dealii::GridGenerator::merge_triangulations(left, right, both);
  for (const auto& cell : both.active_cell_iterators())  // each piece's bottom: 4 on the left, 14 on the right
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary() && cell->face(f)->center()[2] < 1e-9)
        cell->face(f)->set_boundary_id(cell->face(f)->center()[0] < 0.05 ? 4 : 14);
  const LinearElastic material(lame_lambda(5000, 0.3), lame_mu(5000, 0.3));
  QuasiStaticSolver solver(both, material, 1);
  solver.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());  // the left piece's bottom only
  std::vector<Discretisation::Piece> pieces = solver.pieces();
  ASSERT_EQ(pieces.size(), 2u);
  std::sort(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) { return a.cells > b.cells; });
  EXPECT_EQ(pieces[0].cells, 4u);
  EXPECT_TRUE(pieces[0].free_motions.empty());
  EXPECT_EQ(pieces[1].cells, 1u);
  EXPECT_EQ(pieces[1].free_motions.size(), 6u);
  QuasiStaticSolver held(both, material, 1);
  held.prescribe_displacement(4, {true, true, true}, Tensor<1, 3>());
  held.prescribe_displacement(14, {true, true, true}, Tensor<1, 3>());
  for (const Discretisation::Piece& piece : held.pieces()) EXPECT_TRUE(piece.free_motions.empty());
}

// A scene with no support is refused as a physical problem that says what to do, not bad input.
TEST(HeldTissue, ASceneNothingHoldsIsAPhysicalProblem) {
  const std::string text = "name: s\nunits: SI\nmesh:\n  generate: {shape: ball, radius_m: 0.03, refinements: 0}\n"
                           "material: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.3}\n";
  try {
    build_tissue_model(config::parse_scene(text, "s.yaml", ".").scene);
    FAIL() << "a ball held by nothing was built";
  } catch (const PhysicalProblem& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the tissue is not held"), std::string::npos) << what;
    EXPECT_NE(what.find("type fixed"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace fetouch::fem
