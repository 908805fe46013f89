// The deal.II mesh built from a scene's mesh specification, checked against geometry: volumes,
// face areas of named boundary regions, and a hand-written Gmsh file; broken Gmsh files refused.
#include <gtest/gtest.h>

#include <deal.II/grid/tria.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

#include "fem/tissue_mesh_builder.h"
#include "tests/support/test_paths.h"

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

// A thin or coarse shell (the random scenes found it): a flattened face's centre lies well inside its
// sphere, below the middle radius for a shell thinner than about a third of its radius. The two
// surfaces are still similar polyhedra: areas in the ratio (R / r)^2 exactly, for every element.
TEST(GeneratedShell, ThinCoarseShellsNameTheirSurfacesToo) {
  for (const ElementType element : {ElementType::p1, ElementType::q1})
    for (const int refinements : {0, 1, 2})
      for (const double inner_radius : {0.02, 0.03, 0.04, 0.045}) {
        config::MeshSpec spec;
        spec.source = config::MeshSource::generated;
        spec.element = element;
        spec.generated.shape = GeneratedShape::shell;
        spec.generated.radius_m = 0.05;
        spec.generated.inner_radius_m = inner_radius;
        spec.generated.refinements = refinements;
        dealii::Triangulation<3> tria;
        const auto info = build_tissue_mesh(spec, tria);
        const double inner = boundary_area(tria, info.boundary_ids.at("inner"));
        const double outer = boundary_area(tria, info.boundary_ids.at("outer"));
        const double ratio = 0.05 / inner_radius;
        EXPECT_NEAR(outer / inner, ratio * ratio, 1e-9) << config::to_string(element) << " r" << refinements << " inner " << inner_radius;
      }
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

// Broken Gmsh files reached `fetouch solve` and `replay` through deal.II's reader and aborted the
// program (Gmsh throws std::string; issue 17). Each is refused naming the file and the reason, and a
// file that is not a mesh never reaches Gmsh, which would run it as a .geo script: this one would
// create a file through the shell.
TEST(GmshFile, BrokenFilesAreRefusedAndNeverRunAsScripts) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("fetouch_broken_msh_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path marker = dir / "script_ran";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"SystemCall \"touch " + marker.string() + "\";\n", "not a Gmsh mesh"},
      {"garbage\n", "not a Gmsh mesh"},
      {"$MeshFormat\n9.9 0 8\n$EndMeshFormat\n", "9.9"},
      // Checked line by line before Gmsh sees them (meshes/msh_check.h): the line and what is wrong.
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n$EndNodes\n", ".msh:7: expected a positive node tag"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n0\n$EndNodes\n$Elements\n1\n1 4 2 0 1 1 2 3 99\n$EndElements\n",
       ".msh:9: the element names node 1, which $Nodes does not define"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "no $Nodes section"},
  };
  int k = 0;
  for (const auto& [text, expected] : cases) {
    config::MeshSpec spec;
    spec.source = config::MeshSource::file;
    spec.path = dir / ("broken_" + std::to_string(k++) + ".msh");
    std::ofstream(spec.path) << text;
    dealii::Triangulation<3> tria;
    try {
      build_tissue_mesh(spec, tria);
      ADD_FAILURE() << text << ": accepted";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(spec.path.string()), std::string::npos) << what;
      EXPECT_NE(what.find(expected), std::string::npos) << what;
    }
  }
  EXPECT_FALSE(fs::exists(marker)) << "Gmsh ran a file given as a mesh";
  // The good mesh still reads after all that (Gmsh left finalised).
  config::MeshSpec good;
  good.source = config::MeshSource::file;
  good.path = fs::path(FETOUCH_TEST_DATA_DIR) / "data/unit_cube.msh";
  dealii::Triangulation<3> tria;
  EXPECT_EQ(build_tissue_mesh(good, tria).cells, 6u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::fem
