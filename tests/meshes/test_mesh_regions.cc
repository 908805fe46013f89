// Multi-region meshes from a label map (meshes/mesh_regions.h): a ball inside a shell, meshed as
// one conforming mesh whose elements take their region. Checked against the geometry (the regions'
// exact volumes) and, read back from the .vtu with VTK, against conformity: every interface face
// shared by exactly two elements of different regions, no node duplicated across an interface; the
// interface written as its own named surface group.
#include <gtest/gtest.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <array>
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

  // The interface as a surface group of its own: boundary id 2 (after the outer surfaces' 0 and 1),
  // named shell_ball, exactly the faces the two regions share, each facing out of the shell's
  // element that holds it (away from that element's fourth corner).
  auto* boundary = vtkIntArray::SafeDownCast(grid->GetCellData()->GetArray("boundary_id"));
  auto* boundary_names = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("boundary_names"));
  ASSERT_TRUE(boundary && boundary_names);
  ASSERT_EQ(boundary_names->GetNumberOfValues(), 3);
  EXPECT_EQ(boundary_names->GetValue(2), "shell_ball");
  std::map<std::array<vtkIdType, 3>, vtkIdType> shell_corner;  // a shell element's face: its fourth corner
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA || material->GetValue(c) != 1) continue;
    vtkIdType n = 0;
    const vtkIdType* v = nullptr;
    grid->GetCellPoints(c, n, v);
    for (int f = 0; f < 4; ++f) {
      std::array<vtkIdType, 3> face{v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]};
      std::sort(face.begin(), face.end());
      shell_corner[face] = v[f];
    }
  }
  long grouped = 0, outwards = 0, shared = 0;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TRIANGLE || boundary->GetValue(c) != 2) continue;
    vtkIdType n = 0;
    const vtkIdType* v = nullptr;
    grid->GetCellPoints(c, n, v);
    std::array<vtkIdType, 3> face{v[0], v[1], v[2]};
    std::sort(face.begin(), face.end());
    const auto holders = faces.find(face);
    shared += holders != faces.end() && holders->second.size() == 2 && holders->second[0] != holders->second[1];
    ++grouped;
    const auto corner = shell_corner.find(face);
    if (corner == shell_corner.end()) continue;
    double p[4][3];
    for (int k = 0; k < 3; ++k) grid->GetPoint(v[k], p[k]);
    grid->GetPoint(corner->second, p[3]);
    double a[3], b[3], normal[3], out = 0;
    for (int d = 0; d < 3; ++d) a[d] = p[1][d] - p[0][d], b[d] = p[2][d] - p[0][d];
    normal[0] = a[1] * b[2] - a[2] * b[1], normal[1] = a[2] * b[0] - a[0] * b[2], normal[2] = a[0] * b[1] - a[1] * b[0];
    for (int d = 0; d < 3; ++d) out += normal[d] * (p[0][d] - p[3][d]);
    outwards += out > 0;
  }
  EXPECT_EQ(grouped, interface);
  EXPECT_EQ(shared, grouped);
  EXPECT_EQ(outwards, grouped);
  const auto groups = interface_groups(mesh);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].first, "shell_ball");
  EXPECT_EQ(groups[0].second, interface);
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
