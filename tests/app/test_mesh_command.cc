// `fetouch mesh`, the real binary, on the synthetic phantom's label map and on the shared spine
// phantom volume: closed, manifold tetrahedral meshes with no inverted element, whose volume is
// within 3 % of the segmented voxels', reported as JSON, and which the solver's mesh reader loads
// (.msh through deal.II and Gmsh, .vtu through VTK) with the same volume. Label mesh.
#include <gtest/gtest.h>
#include <deal.II/grid/tria.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>

#include "config/scene.h"
#include "fem/mpi_session.h"
#include "fem/tissue_mesh_builder.h"
#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

void check_mesh(const std::string& arguments, const fs::path& out) {
  const auto r = run_command(fetouch("mesh --json " + arguments + " --out " + out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node j = YAML::Load(r.out);
  std::printf("%s: %ld tetrahedra, volume error %+.2f %%, min dihedral %.1f deg, min radius ratio %.3f, %.1f s\n",
              arguments.c_str(), j["tetrahedra"].as<long>(), 100 * j["volume_error"].as<double>(),
              j["quality"]["min_dihedral_deg"].as<double>(), j["quality"]["min_radius_ratio"].as<double>(),
              j["seconds"].as<double>());
  EXPECT_TRUE(j["closed_manifold"].as<bool>());
  EXPECT_EQ(j["quality"]["inverted"].as<long>(), 0);
  EXPECT_EQ(j["quality"]["degenerate"].as<long>(), 0);
  EXPECT_LT(std::abs(j["volume_error"].as<double>()), 0.03);
  // The solver's reader: both files, the same volume and the named surface.
  for (const std::string key : {"msh", "vtu"}) {
    config::MeshSpec spec;
    spec.source = config::MeshSource::file;
    spec.path = j[key].as<std::string>();
    dealii::Triangulation<3> tria;
    const fem::TissueMeshInfo info = fem::build_tissue_mesh(spec, tria);
    EXPECT_EQ(static_cast<long>(info.cells), j["tetrahedra"].as<long>()) << key;
    EXPECT_NEAR(info.volume_m3, j["volume_m3"].as<double>(), 1e-9 * j["volume_m3"].as<double>()) << key;
    EXPECT_TRUE(info.boundary_ids.count("surface")) << key;
  }
}

TEST(MeshCommand, PhantomFetusFromItsLabels) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_mesh_" + std::to_string(::getpid()));
  ASSERT_EQ(run_command(fetouch("phantom --out " + (dir / "phantom").string())).exit_code, 0);
  check_mesh((dir / "phantom" / "phantom_labels.mha").string() + " --labels 3 4 5 6 --size 3", dir / "fetus.msh");
  fs::remove_all(dir);
}

TEST(MeshCommand, SharedSpineVolume) {
  const fs::path volume = fs::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound" /
                          "spine_phantom_freehand_reconstructed.mha";
  if (!fs::exists(volume)) GTEST_SKIP() << "no shared data at " << volume.string();
  const fs::path dir = fs::temp_directory_path() / ("fetouch_mesh_spine_" + std::to_string(::getpid()));
  check_mesh(volume.string() + " --size 2", dir / "spine.msh");
  fs::remove_all(dir);
}

TEST(MeshCommand, EmptySegmentationAndHugeMeshesAreRefused) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_mesh_bad_" + std::to_string(::getpid()));
  ASSERT_EQ(run_command(fetouch("phantom --spacing 4 --out " + (dir / "phantom").string())).exit_code, 0);
  const auto empty = run_command(fetouch("mesh " + (dir / "phantom" / "phantom_labels.mha").string() +
                                         " --labels 9 --out " + (dir / "x.msh").string()));
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_NE(empty.err.find("empty"), std::string::npos) << empty.err;
  const auto huge = run_command(fetouch("mesh " + (dir / "phantom" / "phantom_labels.mha").string() +
                                        " --labels 2 --size 0.01 --out " + (dir / "x.msh").string()));
  EXPECT_EQ(huge.exit_code, 2);
  EXPECT_NE(huge.err.find("memory"), std::string::npos) << huge.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
