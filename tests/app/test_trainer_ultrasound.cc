// The trainer's ultrasound image at mid-press against an independent resampling (label gui): the
// real `fetouch trainer` on the default scene writes, beside its screenshot, the ultrasound image
// (8-bit PNG) and the tissue shown (.vtu with the solver's displacement). Here VTK alone redoes the
// image: the pixel centres of the plane the command reports are probed in the deformed mesh
// (vtkWarpVector, vtkProbeFilter) for the displacement u, moved back to X = x - u, and the phantom's
// B-mode volume written by `fetouch phantom` (the scene's seed) is probed there (trilinear), scaled by
// the reported gain and rounded. The trainer interpolates X by barycentric coordinates in its own
// rasteriser; the two agree to a grey level but for pixels a hair from an element's face, where VTK's
// cell search may pick the neighbour (tolerance: 99 % of the pixels within 1 grey level, the mean
// difference under 0.5). The same image made without the displacement (X = x) must differ.
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMetaImageReader.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkProbeFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWarpVector.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

Eigen::Vector3d vector3(const YAML::Node& n) { return {n[0].as<double>(), n[1].as<double>(), n[2].as<double>()}; }

// The volume (mm) probed at points given in metres: trilinear values, 0 outside, as grey levels.
std::vector<int> grey_at(vtkImageData* volume, const std::vector<Eigen::Vector3d>& points_m, double gain) {
  vtkNew<vtkPoints> points;
  for (const auto& p : points_m) points->InsertNextPoint(1e3 * p.x(), 1e3 * p.y(), 1e3 * p.z());
  vtkNew<vtkPolyData> where;
  where->SetPoints(points);
  vtkNew<vtkProbeFilter> probe;
  probe->SetInputData(where);
  probe->SetSourceData(volume);
  probe->Update();
  vtkDataArray* values = probe->GetOutput()->GetPointData()->GetScalars();
  std::vector<int> grey(points_m.size());
  for (std::size_t i = 0; i < grey.size(); ++i)
    grey[i] = static_cast<int>(std::clamp(std::lround(gain * values->GetComponent(vtkIdType(i), 0)), 0L, 255L));
  return grey;
}

TEST(TrainerUltrasound, TheMidPressImageIsTheVolumeSampledThroughTheSolversDisplacement) {
  ASSERT_TRUE(std::getenv("DISPLAY")) << "run under xvfb-run -a";
  const fs::path dir = fs::temp_directory_path() / ("fetouch_trainer_ultrasound_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = (fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml").string();
  const auto phantom = run_command(fetouch("phantom --seed 1 --spacing 1 --out " + (dir / "phantom").string()));
  ASSERT_EQ(phantom.exit_code, 0) << phantom.err;
  // Mid-press: the scene's poke is 8 mm deep from 1.1 s to 2.1 s.
  const auto r = run_command(fetouch("trainer " + scene + " --duration 1.8 --screenshot " + (dir / "press.png").string() +
                                     " --out " + dir.string() + " --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node view = YAML::Load(r.out)["ultrasound_view"];
  ASSERT_TRUE(view && view["volume"].as<bool>()) << r.out;
  const int columns = view["columns"].as<int>(), rows = view["rows"].as<int>();
  const Eigen::Vector3d centre = vector3(view["centre_m"]), lateral = vector3(view["lateral"]), up = vector3(view["up"]);
  const double width = view["width_m"].as<double>(), height = view["height_m"].as<double>(), gain = view["gain"].as<double>();
  EXPECT_GT(view["frame"].as<long>(), 20);

  // The pixel centres, and the displacement there from the tissue the trainer showed.
  std::vector<Eigen::Vector3d> x;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i)
      x.push_back(centre + ((i + 0.5) / columns - 0.5) * width * lateral + (0.5 - (j + 0.5) / rows) * height * up);
  vtkNew<vtkXMLUnstructuredGridReader> tissue;
  tissue->SetFileName(view["tissue"].as<std::string>().c_str());
  tissue->Update();
  ASSERT_GT(tissue->GetOutput()->GetNumberOfCells(), 1000);
  tissue->GetOutput()->GetPointData()->SetActiveVectors("displacement");
  vtkNew<vtkWarpVector> deformed;
  deformed->SetInputConnection(tissue->GetOutputPort());
  deformed->SetScaleFactor(1.0);
  vtkNew<vtkPoints> pixel_points;
  for (const auto& p : x) pixel_points->InsertNextPoint(p.data());
  vtkNew<vtkPolyData> pixels;
  pixels->SetPoints(pixel_points);
  vtkNew<vtkProbeFilter> in_tissue;
  in_tissue->SetInputData(pixels);
  in_tissue->SetSourceConnection(deformed->GetOutputPort());
  in_tissue->Update();
  vtkDataArray* u = in_tissue->GetOutput()->GetPointData()->GetArray("displacement");
  vtkDataArray* valid = in_tissue->GetOutput()->GetPointData()->GetArray(in_tissue->GetValidPointMaskArrayName());
  ASSERT_TRUE(u && valid);
  std::vector<Eigen::Vector3d> moved_back = x;
  long inside = 0;
  double largest_u = 0;
  for (std::size_t p = 0; p < x.size(); ++p)
    if (valid->GetComponent(vtkIdType(p), 0) != 0) {
      const Eigen::Vector3d d(u->GetComponent(vtkIdType(p), 0), u->GetComponent(vtkIdType(p), 1), u->GetComponent(vtkIdType(p), 2));
      moved_back[p] = x[p] - d;
      largest_u = std::max(largest_u, d.norm());
      ++inside;
    }
  EXPECT_GT(inside, long(x.size()) / 4) << "the plane should cut the tissue";
  EXPECT_GT(largest_u, 2e-3) << "mid-press: millimetres of displacement in the plane";

  vtkNew<vtkMetaImageReader> volume_reader;
  volume_reader->SetFileName((dir / "phantom" / "phantom.mha").string().c_str());
  volume_reader->Update();
  const std::vector<int> expected = grey_at(volume_reader->GetOutput(), moved_back, gain);
  const std::vector<int> undeformed = grey_at(volume_reader->GetOutput(), x, gain);

  vtkNew<vtkPNGReader> png;
  png->SetFileName(view["image"].as<std::string>().c_str());
  png->Update();
  int dims[3];
  png->GetOutput()->GetDimensions(dims);
  ASSERT_EQ(dims[0], columns);
  ASSERT_EQ(dims[1], rows);
  vtkDataArray* shown = png->GetOutput()->GetPointData()->GetScalars();
  long within_one = 0, differs_from_undeformed = 0;
  double sum = 0;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const int grey = static_cast<int>(shown->GetComponent(vtkIdType(rows - 1 - j) * columns + i, 0));  // PNG rows go up in VTK
      const std::size_t p = std::size_t(j) * columns + i;
      within_one += std::abs(grey - expected[p]) <= 1;
      sum += std::abs(grey - expected[p]);
      differs_from_undeformed += std::abs(grey - undeformed[p]) > 8;
    }
  const double n = double(columns) * rows;
  std::printf("%ld pixels in the tissue, largest displacement in the plane %.2f mm; %.2f %% within 1 grey level of the "
              "VTK resampling, mean difference %.3f; %.1f %% differ by more than 8 from the undeformed slice\n",
              inside, 1e3 * largest_u, 100 * within_one / n, sum / n, 100 * differs_from_undeformed / n);
  EXPECT_GE(within_one, 0.99 * n);
  EXPECT_LT(sum / n, 0.5);
  EXPECT_GT(differs_from_undeformed, 0.02 * n) << "the press should show in the image";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
