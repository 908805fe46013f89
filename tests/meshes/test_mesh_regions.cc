// Multi-region meshes from a label map (meshes/mesh_regions.h): a ball inside a shell, meshed as
// one conforming mesh whose elements take their region. Checked against the geometry (the regions'
// exact volumes) and, read back from the .vtu with VTK, against conformity: every interface face
// shared by exactly two elements of different regions, no node duplicated across an interface.
#include <gtest/gtest.h>
#include <vtkCellData.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "meshes/mesh_regions.h"
#include "tests/support/tet_faces.h"

namespace fetouch::meshes {
namespace {

constexpr double kInner = 15, kOuter = 32;  // mm

// Label 2 inside radius kInner, 1 out to kOuter, 0 beyond; 1 mm voxels about (45, 45, 45).
MaskVolume labels() {
  MaskVolume v;
  v.dimensions = {90, 90, 90};
  v.data.assign(90 * 90 * 90, 0);
  for (int k = 0; k < 90; ++k)
    for (int j = 0; j < 90; ++j)
      for (int i = 0; i < 90; ++i) {
        const double r = std::sqrt((i - 45.0) * (i - 45.0) + (j - 45.0) * (j - 45.0) + (k - 45.0) * (k - 45.0));
        v.data[(std::size_t(k) * 90 + j) * 90 + i] = r < kInner ? 2 : r < kOuter ? 1 : 0;
      }
  return v;
}

VolumeMesh ball_in_shell(double size_mm) {
  const MaskVolume map = labels();
  MaskVolume union_mask = map;
  for (auto& v : union_mask.data) v = v != 0;
  MeshingSettings settings;
  settings.element_size_mm = size_mm;
  VolumeMesh mesh = mesh_mask(union_mask, settings);
  assign_regions(mesh, map, {parse_region("shell=1"), parse_region("ball=2")});
  return mesh;
}

TEST(MeshRegions, RegionsKeepTheirVolumesAndQuality) {
  const VolumeMesh mesh = ball_in_shell(4);
  ASSERT_EQ(mesh.regions.size(), 2u);
  const double pi = std::acos(-1.0);
  const double ball = 4 * pi / 3 * kInner * kInner * kInner * 1e-9;
  const double shell = 4 * pi / 3 * (kOuter * kOuter * kOuter - kInner * kInner * kInner) * 1e-9;
  const auto& s = mesh.regions[0];
  const auto& b = mesh.regions[1];
  EXPECT_EQ(s.name, "shell");
  EXPECT_EQ(b.name, "ball");
  EXPECT_NEAR(b.volume_m3 / b.voxel_volume_m3, 1, 0.03);
  EXPECT_NEAR(s.volume_m3 / s.voxel_volume_m3, 1, 0.03);
  EXPECT_NEAR(b.volume_m3 / ball, 1, 0.03);
  EXPECT_NEAR(s.volume_m3 / shell, 1, 0.03);
  EXPECT_GE(b.min_dihedral_deg, 10);
  EXPECT_GE(s.min_dihedral_deg, 10);
  EXPECT_EQ(b.outer_triangles, 0);  // the ball is inside: all its faces are interior
  EXPECT_EQ(s.outer_triangles, static_cast<long>(mesh.boundary.size()));
  // The interface is about the sphere of radius kInner: some hundred element faces.
  EXPECT_GT(mesh.interface_triangles, 4 * pi * kInner * kInner / (4 * 4));
}

TEST(MeshRegions, TheVtuIsConformingAcrossTheInterface) {
  const VolumeMesh mesh = ball_in_shell(5);
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "fetouch_mesh_regions.vtu";
  write_volume_mesh(mesh, file);
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName(file.string().c_str());
  reader->Update();
  std::filesystem::remove(file);
  vtkUnstructuredGrid* grid = reader->GetOutput();
  auto* material = vtkIntArray::SafeDownCast(grid->GetCellData()->GetArray("material_id"));
  auto* names = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("region_names"));
  ASSERT_TRUE(material && names);
  EXPECT_EQ(names->GetValue(1), "shell");
  EXPECT_EQ(names->GetValue(2), "ball");
  // No two points at the same place: the regions share their interface nodes.
  EXPECT_TRUE(fetouch::testing::duplicated_points(grid).empty());
  // Every face of a tetrahedron: which elements (regions) hold it.
  const fetouch::testing::TetFaces faces = fetouch::testing::tet_faces(grid, material);
  std::set<int> regions;
  for (const auto& [face, holders] : faces) regions.insert(holders.begin(), holders.end());
  EXPECT_EQ(regions, (std::set<int>{1, 2}));
  long interface = 0, outer = 0;
  for (const auto& [face, holders] : faces) {
    ASSERT_LE(holders.size(), 2u);
    if (holders.size() == 1) ++outer;
    else interface += holders[0] != holders[1];
  }
  EXPECT_EQ(interface, mesh.interface_triangles);
  EXPECT_GT(interface, 0);
  EXPECT_EQ(outer, static_cast<long>(mesh.boundary.size()));
}

TEST(MeshRegions, RegionTextsAreCheckedAndLabelsBelongToOneRegion) {
  const MeshRegion fetus = parse_region("fetus=3,4,5,6");
  EXPECT_EQ(fetus.name, "fetus");
  EXPECT_EQ(fetus.labels, (std::vector<int>{3, 4, 5, 6}));
  for (const char* bad : {"fetus", "=3", "a b=1", "x=0", "x=1,,2", "x=256", "x=", "x=2.5"})
    EXPECT_THROW(parse_region(bad), std::invalid_argument) << bad;
  VolumeMesh mesh;
  EXPECT_THROW(assign_regions(mesh, labels(), {parse_region("a=1,2"), parse_region("b=2")}), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::meshes
