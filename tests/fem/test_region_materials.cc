// A material per region (`materials:` in the scene): a bar of two regions meshed conformingly by
// Gmsh, each a named volume physical group, pulled along its axis. With Poisson's ratio 0 and
// rollers on three coordinate planes the stress is uniaxial, sigma = t, so the displacement is the
// closed form of two springs in series, u_x = t x / E1 up to the interface and
// t (L1 / E1 + (x - L1) / E2) beyond it; P1 elements reproduce it exactly.
#include <gmsh.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "config/scene_loader.h"
#include "fem/tissue_model.h"
#include "meshes/mesh_regions.h"

namespace fetouch::fem {
namespace {

namespace fs = std::filesystem;

constexpr double kL1 = 0.04, kL2 = 0.06, kWidth = 0.02;

// soft: x in [0, L1], hard: x in [L1, L1 + L2]; surfaces left (x = 0), right (x = L), y0, z0.
fs::path two_region_bar() {
  const fs::path file = fs::temp_directory_path() / ("fetouch_two_regions_" + std::to_string(::getpid()) + ".msh");
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("bar");
  const int soft = gmsh::model::occ::addBox(0, 0, 0, kL1, kWidth, kWidth);
  const int hard = gmsh::model::occ::addBox(kL1, 0, 0, kL2, kWidth, kWidth);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> map;
  gmsh::model::occ::fragment({{3, soft}}, {{3, hard}}, out, map);  // one shared interface
  gmsh::model::occ::synchronize();
  const auto in_box = [](double x0, double y0, double z0, double x1, double y1, double z1, int dim) {
    gmsh::vectorpair found;
    gmsh::model::getEntitiesInBoundingBox(x0, y0, z0, x1, y1, z1, found, dim);
    std::vector<int> tags;
    for (const auto& [d, tag] : found) tags.push_back(tag);
    return tags;
  };
  const double e = 1e-6, l = kL1 + kL2;
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, in_box(-e, -e, -e, kL1 + e, 1, 1, 3), 7), "soft");
  gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, in_box(kL1 - e, -e, -e, l + e, 1, 1, 3), 9), "hard");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, in_box(-e, -e, -e, e, 1, 1, 2), 1), "left");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, in_box(l - e, -e, -e, l + e, 1, 1, 2), 2), "right");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, in_box(-e, -e, -e, 1, e, 1, 2), 3), "y0");
  gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, in_box(-e, -e, -e, 1, 1, e, 2), 4), "z0");
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.008);
  gmsh::model::mesh::generate(3);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::write(file.string());
  gmsh::finalize();
  return file;
}

std::string bar_scene(const fs::path& mesh, const std::string& materials) {
  return "name: bar\nunits: SI\nmesh: {file: " + mesh.string() + ", element: p1}\n" + materials +
         "boundary:\n"
         "  - {name: left, type: fixed, components: [x], select: {physical_group: left}}\n"
         "  - {name: y0, type: fixed, components: [y], select: {physical_group: y0}}\n"
         "  - {name: z0, type: fixed, components: [z], select: {physical_group: z0}}\n"
         "  - {name: pull, type: traction, traction_pa: [100, 0, 0], select: {physical_group: right}}\n"
         "solver: {newton: {relative_tolerance: 1.0e-12}}\n";
}

std::unique_ptr<TissueModel> model(const std::string& text) {
  return build_tissue_model(config::parse_scene(text, "bar.yaml", ".").scene);
}

class RegionMaterials : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { mesh_ = new fs::path(two_region_bar()); }
  static void TearDownTestSuite() {
    fs::remove(*mesh_);
    delete mesh_;
  }
  static fs::path* mesh_;
};
fs::path* RegionMaterials::mesh_ = nullptr;

TEST_F(RegionMaterials, TwoRegionsInSeriesStretchAsTheirSprings) {
  const double e1 = 2000, e2 = 8000, t = 100;
  auto m = model(bar_scene(*mesh_,
                           "materials:\n"
                           "  soft: {model: linear_elastic, youngs_modulus_pa: 2000, poisson_ratio: 0}\n"
                           "  hard: {model: linear_elastic, youngs_modulus_pa: 8000, poisson_ratio: 0}\n"));
  ASSERT_EQ(m->mesh.regions.size(), 2u);
  EXPECT_EQ(m->mesh.regions[0].name, "soft");
  EXPECT_EQ(m->mesh.regions[1].name, "hard");
  EXPECT_NEAR(m->mesh.regions[0].volume_m3, kL1 * kWidth * kWidth, 1e-12);
  EXPECT_NEAR(m->mesh.regions[1].volume_m3, kL2 * kWidth * kWidth, 1e-12);
  ASSERT_TRUE(m->solver->solve(m->newton).converged);
  const auto exact = [&](const dealii::Point<3>& x) {
    dealii::Tensor<1, 3> u;
    u[0] = x[0] <= kL1 ? t * x[0] / e1 : t * (kL1 / e1 + (x[0] - kL1) / e2);
    return u;
  };
  const double end = t * (kL1 / e1 + kL2 / e2);  // 3.75 mm
  EXPECT_LT(m->solver->max_nodal_error(exact), 1e-9 * end);
  // The one-region shorthand with the soft material everywhere stretches as one soft bar.
  auto uniform = model(bar_scene(*mesh_, "material: {model: linear_elastic, youngs_modulus_pa: 2000, poisson_ratio: 0}\n"));
  ASSERT_TRUE(uniform->solver->solve(uniform->newton).converged);
  EXPECT_NEAR(uniform->solver->displacement_at(dealii::Point<3>(kL1 + kL2, 0.01, 0.01))[0], t * (kL1 + kL2) / e1,
              1e-9 * end);
  // `material:` beside `materials:` is every other region's.
  auto mixed = model(bar_scene(*mesh_,
                               "material: {model: linear_elastic, youngs_modulus_pa: 2000, poisson_ratio: 0}\n"
                               "materials:\n"
                               "  9: {model: linear_elastic, youngs_modulus_pa: 8000, poisson_ratio: 0}\n"));
  ASSERT_TRUE(mixed->solver->solve(mixed->newton).converged);
  EXPECT_LT(mixed->solver->max_nodal_error(exact), 1e-9 * end);
}

TEST_F(RegionMaterials, MissingAndUnknownRegionsAreNamedWithTheirLine) {
  const auto error = [&](const std::string& materials) {
    try {
      model(bar_scene(*mesh_, materials));
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Only `materials:`, and the hard region left out: it is named, with its cell count.
  const std::string missing = error("materials:\n  soft: {model: neo_hookean, youngs_modulus_pa: 2000, poisson_ratio: 0.3}\n");
  EXPECT_NE(missing.find("region hard (id 9)"), std::string::npos) << missing;
  EXPECT_NE(missing.find("has no material"), std::string::npos) << missing;
  // A region the mesh does not have: the key, its line and the closest name.
  const std::string unknown = error(
      "material: {model: neo_hookean, youngs_modulus_pa: 2000, poisson_ratio: 0.3}\n"
      "materials:\n  sotf: {model: neo_hookean, youngs_modulus_pa: 2000, poisson_ratio: 0.3}\n");
  EXPECT_NE(unknown.find("materials.sotf (line 6)"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("did you mean 'soft'"), std::string::npos) << unknown;
  // Neither `material:` nor `materials:`: the loader says so.
  EXPECT_THROW(config::parse_scene(bar_scene(*mesh_, ""), "bar.yaml", "."), config::SceneError);
}

// A cavity by regions, named as the scene names them: the soft half of the bar holds it, so its
// reference volume is that box's, L1 w^2 (exact: flat faces); a region the mesh lacks is named.
TEST_F(RegionMaterials, ACavityByRegionsHoldsThoseRegionsVolume) {
  const std::string materials = "material: {model: neo_hookean, youngs_modulus_pa: 2000, poisson_ratio: 0.3}\n";
  const auto built = model(bar_scene(*mesh_, materials) + "effects:\n  - cavity: {regions: [soft]}\n");
  EXPECT_NEAR(built->solver->cavity_reference_volume(), kL1 * kWidth * kWidth, 1e-12 * kL1 * kWidth * kWidth);
  const auto by_id = model(bar_scene(*mesh_, materials) + "effects:\n  - cavity: {regions: [9]}\n");
  EXPECT_NEAR(by_id->solver->cavity_reference_volume(), kL2 * kWidth * kWidth, 1e-12 * kL2 * kWidth * kWidth);
  try {
    model(bar_scene(*mesh_, materials) + "effects:\n  - cavity: {regions: [fluid]}\n");
    ADD_FAILURE() << "a cavity of a region the mesh lacks was built";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no volume region fluid"), std::string::npos) << e.what();
  }
}

// `fetouch mesh --regions` output read back by the solver: a ball (label 2) in a shell (label 1),
// written as .msh and as .vtu; deal.II sees the regions by name with the mesher's cells and volumes,
// and a scene gives each its material by that name. The interface's own surface group (inner faces,
// which deal.II cannot hold as boundary) is in both files and does not stop the solver reading them.
TEST(MeshedRegions, RegionsOfTheMesherAreTheSolversByName) {
  meshes::MaskVolume map;
  map.dimensions = {60, 60, 60};
  map.data.assign(60 * 60 * 60, 0);
  for (int k = 0; k < 60; ++k)
    for (int j = 0; j < 60; ++j)
      for (int i = 0; i < 60; ++i) {
        const double r = std::sqrt((i - 30.0) * (i - 30.0) + (j - 30.0) * (j - 30.0) + (k - 30.0) * (k - 30.0));
        map.data[(std::size_t(k) * 60 + j) * 60 + i] = r < 10 ? 2 : r < 22 ? 1 : 0;
      }
  meshes::MaskVolume mask = map;
  for (auto& v : mask.data) v = v != 0;
  meshes::MeshingSettings settings;
  settings.element_size_mm = 5;
  meshes::VolumeMesh mesh = meshes::mesh_mask(mask, settings);
  meshes::assign_regions(mesh, map, {meshes::parse_region("shell=1"), meshes::parse_region("ball=2")});
  for (const char* extension : {".msh", ".vtu"}) {
    const fs::path file = fs::temp_directory_path() / (std::string("fetouch_meshed_regions") + extension);
    meshes::write_volume_mesh(mesh, file);
    auto m = model("name: r\nmesh: {file: " + file.string() + ", element: p1}\n"
                   "materials:\n"
                   "  shell: {model: neo_hookean, youngs_modulus_pa: 2000, poisson_ratio: 0.45}\n"
                   "  ball: {model: neo_hookean, youngs_modulus_pa: 60000, poisson_ratio: 0.45}\n"
                   "boundary:\n  - {name: skin, type: fixed, select: {physical_group: shell_outer}}\n");
    if (std::string(extension) == ".msh") {  // the interface is a named surface group of its own
      gmsh::initialize();
      gmsh::option::setNumber("General.Terminal", 0);
      gmsh::open(file.string());
      gmsh::vectorpair groups;
      gmsh::model::getPhysicalGroups(groups, 2);
      std::size_t interface_faces = 0;
      for (const auto& [dim, tag] : groups) {
        std::string name;
        gmsh::model::getPhysicalName(dim, tag, name);
        if (name != "shell_ball") continue;
        std::vector<int> entities;
        gmsh::model::getEntitiesForPhysicalGroup(dim, tag, entities);
        for (const int entity : entities) {
          std::vector<std::size_t> tags, nodes;
          gmsh::model::mesh::getElementsByType(2, tags, nodes, entity);
          interface_faces += tags.size();
        }
      }
      gmsh::finalize();
      EXPECT_EQ(long(interface_faces), mesh.interface_triangles);
      EXPECT_GT(interface_faces, 0u);
    }
    fs::remove(file);
    ASSERT_EQ(m->mesh.regions.size(), 2u) << extension;
    for (int r = 0; r < 2; ++r) {
      EXPECT_EQ(m->mesh.regions[r].name, mesh.regions[r].name) << extension;
      EXPECT_EQ(m->mesh.regions[r].material_id, unsigned(r + 1)) << extension;
      EXPECT_EQ(long(m->mesh.regions[r].cells), mesh.regions[r].tetrahedra) << extension;
      EXPECT_NEAR(m->mesh.regions[r].volume_m3, mesh.regions[r].volume_m3, 1e-12) << extension;
    }
    EXPECT_DOUBLE_EQ(m->region_materials.at(2)->shear_modulus(), lame_mu(60000, 0.45)) << extension;
    EXPECT_EQ(m->region_faces.at("skin"), static_cast<unsigned int>(mesh.boundary.size())) << extension;
  }
}

}  // namespace
}  // namespace fetouch::fem
