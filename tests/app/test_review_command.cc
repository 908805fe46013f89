// `fetouch review`, the real binary (label gui): a folder that is not a take, a take without its
// anatomy, an anatomy that is not a mesh, an assessment that is not one, a time past the take's
// end, and no display, are each
// refused with exit 2 and a line naming the file or the value; a plain take (not an exercise's) on
// a one-tetrahedron anatomy opens under Xvfb and writes its screenshot. The exercise's review is
// checked on a real take in test_trainer_exercise.cc.
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellType.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>

#include "app/recording.h"
#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

// A take of 2 s: one probe going down through z = 0.02 m and back, in contact below it.
void write_take(const fs::path& file) {
  app::RecordingHeader h;
  h.program_version = "fetouch test";
  h.scene_path = "/nowhere/scene.yaml";  // unreadable: the probe's radius falls back to 5 mm
  h.probes = {"probe"};
  app::RecordingWriter writer(file, h);
  std::vector<app::DeviceSample> samples(2001);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    app::DeviceSample& s = samples[k];
    s.time_s = 1e-3 * k;
    const double z = 0.03 - 0.02 * std::sin(M_PI * s.time_s / 2);
    s.position = s.proxy = Eigen::Vector3d(0.01, 0.01, z);
    s.in_contact = z < 0.02;
    s.force = Eigen::Vector3d(0, 0, s.in_contact ? 300 * (0.02 - z) : 0);
  }
  writer.append(0, samples.data(), samples.size());
  writer.commit();
}

// One tetrahedron, 2 cm on a side, without region names.
void write_anatomy(const fs::path& file) {
  vtkNew<vtkPoints> points;
  for (const auto& p : {std::array<double, 3>{0, 0, 0}, {0.02, 0, 0}, {0, 0.02, 0}, {0, 0, 0.02}}) points->InsertNextPoint(p.data());
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  const vtkIdType ids[4] = {0, 1, 2, 3};
  grid->InsertNextCell(VTK_TETRA, 4, ids);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputData(grid);
  ASSERT_EQ(writer->Write(), 1);
}

TEST(ReviewCommand, WhatIsNotAReviewableTakeIsRefusedNamingTheFile) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_review_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  auto r = run_command(fetouch("review " + (dir / "none").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "none").string() + ": no such folder"), std::string::npos) << r.err;

  fs::create_directories(dir);
  r = run_command(fetouch("review " + dir.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "take.h5").string() + ": no such recording"), std::string::npos) << r.err;

  write_take(dir / "take.h5");
  r = run_command(fetouch("review " + dir.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "anatomy.vtu").string() + ": no such file"), std::string::npos) << r.err;

  std::ofstream(dir / "anatomy.vtu") << "<VTKFile>not a mesh\n";
  r = run_command(fetouch("review " + dir.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "anatomy.vtu").string() + ": not a VTK unstructured grid"), std::string::npos) << r.err;

  // Another take's name: its anatomy is STEM.anatomy.vtu.
  fs::copy_file(dir / "take.h5", dir / "take-3.h5");
  r = run_command(fetouch("review " + dir.string() + " --take take-3.h5"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "take-3.anatomy.vtu").string() + ": no such file"), std::string::npos) << r.err;

  write_anatomy(dir / "anatomy.vtu");
  std::ofstream(dir / "assessment.json") << "{\"pose\": 3}\n";
  r = run_command(fetouch("review " + dir.string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "assessment.json").string() + ": not an exercise's assessment"), std::string::npos) << r.err;
  fs::remove(dir / "assessment.json");

  r = run_command(fetouch("review " + dir.string() + " --at 2.5 --screenshot " + (dir / "x.png").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--at 2.5: the take lasts 2.000 s"), std::string::npos) << r.err;

  r = run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + fetouch("review " + dir.string() + " --screenshot " + (dir / "x.png").string()));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "x.png"));

  if (std::getenv("DISPLAY")) {
    r = run_command(fetouch("review " + dir.string() + " --at 1 --screenshot " + (dir / "x.png").string() + " --json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const YAML::Node j = YAML::Load(r.out);
    EXPECT_FALSE(j["exercise"].as<bool>());
    EXPECT_DOUBLE_EQ(j["duration_s"].as<double>(), 2.0);
    EXPECT_DOUBLE_EQ(j["at_s"].as<double>(), 1.0);
    // In contact while z < 0.02: sin(pi t / 2) > 1/2, t in (1/3, 5/3) s; the deepest press 6 mm at 300 N/m.
    EXPECT_NEAR(j["probes"][0]["in_contact_s"].as<double>(), 4.0 / 3, 2e-3);
    EXPECT_NEAR(j["probes"][0]["largest_force_n"].as<double>(), 300 * 0.01, 1e-6);
    EXPECT_TRUE(fs::exists(dir / "x.png"));
  }
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
