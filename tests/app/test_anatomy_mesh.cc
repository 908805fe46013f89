// The anatomy scene's mesh (issue 15's conformity acceptance): `fetouch solve` meshes the shipped
// default scene (fetus_phantom.yaml, the anatomy) into an empty cache, and the cached .vtu is read back with VTK and checked
// against the phantom's label map (made here by the imaging library, the ground truth the mesher
// starts from): every interface face held by exactly two tetrahedra of different regions, no point
// twice, each region's volume within 3 % of its labels' voxels, every region's smallest dihedral
// angle at least 10 degrees.
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellData.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "imaging/phantom.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"
#include "tests/support/tet_faces.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

// The smallest of a tetrahedron's six dihedral angles, degrees.
double min_dihedral_deg(const std::array<Eigen::Vector3d, 4>& p) {
  double smallest = 180;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      // The edge (a, b) and the two faces through it, with the other vertices c and d.
      int others[2], k = 0;
      for (int v = 0; v < 4; ++v)
        if (v != a && v != b) others[k++] = v;
      const Eigen::Vector3d e = (p[b] - p[a]).normalized();
      Eigen::Vector3d u = p[others[0]] - p[a], w = p[others[1]] - p[a];
      u -= u.dot(e) * e, w -= w.dot(e) * e;
      smallest = std::min(smallest, std::acos(std::clamp(u.normalized().dot(w.normalized()), -1.0, 1.0)) * 180 / M_PI);
    }
  return smallest;
}

TEST(AnatomyMesh, RegionsAreConformingKeepTheirVolumesAndQuality) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_anatomy_mesh_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scene = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_phantom.yaml";
  const auto r = run_command("FETOUCH_CACHE_DIR=" + (dir / "cache").string() + " " +
                             fetouch("solve --steps 1 --out " + (dir / "solve").string() + " " + scene.string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<fs::path> cached;
  for (const auto& entry : fs::directory_iterator(dir / "cache" / "meshes"))
    if (entry.path().extension() == ".vtu") cached.push_back(entry.path());
  ASSERT_EQ(cached.size(), 1u);

  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName(cached[0].c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  auto* material = vtkIntArray::SafeDownCast(grid->GetCellData()->GetArray("material_id"));
  auto* names = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("region_names"));
  ASSERT_TRUE(material && names);
  const std::vector<std::string> regions{"wall", "fluid", "head", "body"};
  for (int id = 1; id <= 4; ++id) EXPECT_EQ(names->GetValue(id), regions[id - 1]);

  EXPECT_TRUE(duplicated_points(grid).empty());
  std::map<int, double> volume_m3, smallest_deg;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA) continue;
    vtkIdType n = 0;
    const vtkIdType* v = nullptr;
    grid->GetCellPoints(c, n, v);
    const int region = material->GetValue(c);
    std::array<Eigen::Vector3d, 4> x;
    for (int k = 0; k < 4; ++k) grid->GetPoint(v[k], x[k].data());
    volume_m3[region] += std::abs((x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0]))) / 6;
    smallest_deg.try_emplace(region, 180);
    smallest_deg[region] = std::min(smallest_deg[region], min_dihedral_deg(x));
  }
  long interface = 0;
  std::set<std::pair<int, int>> touching;
  for (const auto& [face, holders] : tet_faces(grid, material)) {
    ASSERT_LE(holders.size(), 2u);
    if (holders.size() == 2 && holders[0] != holders[1]) {
      ++interface;
      touching.insert({std::min(holders[0], holders[1]), std::max(holders[0], holders[1])});
    }
  }
  EXPECT_GT(interface, 0);
  EXPECT_TRUE(touching.count({1, 2}));  // wall | fluid
  EXPECT_TRUE(touching.count({2, 4}));  // fluid | body

  // The labels' voxels, from the phantom the scene names (seed 1, 1 mm, the fetus 31 mm up).
  imaging::PhantomSettings settings;
  settings.speckle = false;
  settings.fetus_offset_mm = {0, 0, 31};
  const imaging::Phantom phantom = imaging::make_phantom(settings);
  std::map<int, double> voxels_m3;
  const std::map<int, int> region_of{{1, 1}, {2, 2}, {3, 3}, {4, 3}, {5, 4}, {6, 4}};
  for (const auto label : phantom.labels.data)
    if (label != 0) voxels_m3[region_of.at(label)] += phantom.labels.voxel_volume_mm3() * 1e-9;
  for (int id = 1; id <= 4; ++id) {
    std::printf("%-5s: %.2f cm^3 meshed, %.2f cm^3 of voxels (%+.2f %%), smallest dihedral %.1f deg\n",
                regions[id - 1].c_str(), volume_m3[id] * 1e6, voxels_m3[id] * 1e6,
                100 * (volume_m3[id] / voxels_m3[id] - 1), smallest_deg[id]);
    EXPECT_NEAR(volume_m3[id] / voxels_m3[id], 1, 0.03) << regions[id - 1];
    EXPECT_GE(smallest_deg[id], 10) << regions[id - 1];
  }
  std::printf("%ld interface faces, %lld points, %ld tetrahedra\n", interface, static_cast<long long>(grid->GetNumberOfPoints()),
              static_cast<long>(grid->GetNumberOfCells()));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
