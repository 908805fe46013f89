// Summaries of the hand-written unit cube in both formats (tests/data/README.md).
#include <gtest/gtest.h>

#include <fstream>

#include "meshes/mesh_summary.h"
#include "tests/support/test_paths.h"

namespace fetouch::meshes {
namespace {

const std::filesystem::path kData = std::filesystem::path(FETOUCH_TEST_DATA_DIR) / "data";

TEST(MeshSummary, GmshUnitCube) {
  const MeshSummary s = read_mesh_summary(kData / "unit_cube.msh");
  EXPECT_EQ(s.nodes, 8);
  EXPECT_EQ(s.count("tetrahedron"), 6);
  EXPECT_EQ(s.count("triangle"), 4);
  EXPECT_TRUE(s.has_group("bottom"));
  EXPECT_TRUE(s.has_group("top"));
  EXPECT_TRUE(s.has_group("tissue"));
  EXPECT_FALSE(s.has_group("side"));
  EXPECT_EQ(s.min_m, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(s.max_m, (std::array<double, 3>{1, 1, 1}));
}

TEST(MeshSummary, VtuUnitCube) {
  const MeshSummary s = read_mesh_summary(kData / "unit_cube.vtu");
  EXPECT_EQ(s.nodes, 8);
  EXPECT_EQ(s.count("tetrahedron"), 6);
  EXPECT_EQ(s.max_m, (std::array<double, 3>{1, 1, 1}));
}

TEST(MeshSummary, BadFilesAreErrors) {
  const auto dir = std::filesystem::temp_directory_path() / ("fetouch_mesh_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "text.msh") << "hello\n";
  std::ofstream(dir / "text.vtu") << "hello\n";
  EXPECT_THROW(read_mesh_summary(dir / "text.msh"), std::runtime_error);
  EXPECT_THROW(read_mesh_summary(dir / "text.vtu"), std::runtime_error);
  EXPECT_THROW(read_mesh_summary(dir / "missing.msh"), std::runtime_error);
  EXPECT_THROW(read_mesh_summary(kData / "poke.csv"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::meshes
