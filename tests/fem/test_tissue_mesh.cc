// The deal.II mesh built from a scene's mesh specification, checked against geometry: volumes,
// face areas of named boundary regions, and a hand-written Gmsh file.
#include <gtest/gtest.h>

#include <deal.II/grid/tria.h>

#include <cmath>

#include "fem/tissue_mesh_builder.h"

namespace fetouch::fem {
namespace {

using config::ElementType;
using config::GeneratedShape;

config::MeshSpec generated_box(ElementType element) {
  config::MeshSpec spec;
  spec.source = config::MeshSource::generated;
  spec.element = element;
  spec.generated.shape = GeneratedShape::box;
  spec.generated.size_m = {0.1, 0.08, 0.05};
  spec.generated.refinements = 1;
  return spec;
}

// Sum of the areas of boundary faces with the given id.
double boundary_area(const dealii::Triangulation<3>& tria, unsigned int id) {
  double area = 0;
  for (const auto& cell : tria.active_cell_iterators())
    for (const auto f : cell->face_indices())
      if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == id)
        area += cell->face(f)->measure();
  return area;
}

class GeneratedBox : public ::testing::TestWithParam<ElementType> {};

TEST_P(GeneratedBox, VolumeAndNamedFacesMatchTheBox) {
  dealii::Triangulation<3> tria;
  const auto info = build_tissue_mesh(generated_box(GetParam()), tria);
  // Straight-sided cells tile a box exactly: round-off only.
  EXPECT_NEAR(info.volume_m3, 0.1 * 0.08 * 0.05, 1e-15);
  const bool simplex = GetParam() == ElementType::p1 || GetParam() == ElementType::p2;
  EXPECT_EQ(info.simplex, simplex);
  ASSERT_EQ(info.boundary_ids.size(), 6u);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("zmin")), 0.1 * 0.08, 1e-15);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("zmax")), 0.1 * 0.08, 1e-15);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("xmin")), 0.08 * 0.05, 1e-15);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("ymax")), 0.1 * 0.05, 1e-15);
}

INSTANTIATE_TEST_SUITE_P(Elements, GeneratedBox,
                         ::testing::Values(ElementType::p1, ElementType::p2, ElementType::q1,
                                           ElementType::q2));

TEST(GeneratedBall, VolumeConvergesToTheSphereFromBelow) {
  // Straight-sided cells inscribed in the sphere: the volume approaches 4/3 pi r^3 from below as the
  // mesh is refined, the gap shrinking roughly fourfold per refinement (second order in h).
  config::MeshSpec spec;
  spec.source = config::MeshSource::generated;
  spec.element = ElementType::p1;
  spec.generated.shape = GeneratedShape::ball;
  spec.generated.radius_m = 0.05;
  const double exact = 4.0 / 3.0 * M_PI * std::pow(0.05, 3);
  double previous_gap = 1;
  for (int refinements = 1; refinements <= 3; ++refinements) {
    spec.generated.refinements = refinements;
    const double gap = (exact - inspect_tissue_mesh(spec).volume_m3) / exact;
    EXPECT_GT(gap, 0);
    EXPECT_LT(gap, previous_gap / 2.5) << refinements;
    previous_gap = gap;
  }
  EXPECT_LT(previous_gap, 0.02);
}

TEST(GeneratedShell, InnerAndOuterSurfacesAreNamed) {
  config::MeshSpec spec;
  spec.source = config::MeshSource::generated;
  spec.element = ElementType::q1;
  spec.generated.shape = GeneratedShape::shell;
  spec.generated.radius_m = 0.05;
  spec.generated.inner_radius_m = 0.03;
  spec.generated.refinements = 2;
  dealii::Triangulation<3> tria;
  const auto info = build_tissue_mesh(spec, tria);
  // Inscribed polyhedral surfaces: areas under 4 pi r^2 (by 6 % at 12 x 8 flat faces per sphere,
  // a second-order gap), and exactly in the ratio (5/3)^2 since the two surfaces are similar.
  const double inner = boundary_area(tria, info.boundary_ids.at("inner"));
  const double outer = boundary_area(tria, info.boundary_ids.at("outer"));
  EXPECT_LT(inner, 4 * M_PI * 0.03 * 0.03);
  EXPECT_GT(inner, 0.9 * 4 * M_PI * 0.03 * 0.03);
  EXPECT_NEAR(outer / inner, 25.0 / 9.0, 1e-9);
}

TEST(GmshFile, HandWrittenUnitCube) {
  config::MeshSpec spec;
  spec.source = config::MeshSource::file;
  spec.path = std::filesystem::path(FETOUCH_TEST_DATA_DIR) / "data/unit_cube.msh";
  dealii::Triangulation<3> tria;
  const auto info = build_tissue_mesh(spec, tria);
  EXPECT_EQ(info.cells, 6u);
  EXPECT_EQ(info.vertices, 8u);
  EXPECT_NEAR(info.volume_m3, 1.0, 1e-14);
  ASSERT_EQ(info.boundary_ids.count("bottom"), 1u);
  ASSERT_EQ(info.boundary_ids.count("top"), 1u);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("bottom")), 1.0, 1e-14);
  EXPECT_NEAR(boundary_area(tria, info.boundary_ids.at("top")), 1.0, 1e-14);
}

TEST(TissueMesh, ElementTypeMustSuitTheCells) {
  config::MeshSpec spec;
  spec.source = config::MeshSource::file;
  spec.path = std::filesystem::path(FETOUCH_TEST_DATA_DIR) / "data/unit_cube.msh";
  spec.element = ElementType::q1;  // hexahedral elements on a tetrahedral mesh
  EXPECT_THROW(inspect_tissue_mesh(spec), std::runtime_error);
  spec.source = config::MeshSource::volume;
  EXPECT_THROW(inspect_tissue_mesh(spec), std::runtime_error);
}

}  // namespace
}  // namespace fetouch::fem
