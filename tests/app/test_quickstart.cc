// The README's first command, as a user runs it: scripts/quickstart (set-up and build are already
// done here, so they check and do nothing), whose main job replays the default scene. It must end
// well, say where the outputs are, and those outputs must open in VTK's readers (ParaView's): the
// PVD collection parsed by VTK's XML parser, every VTU it lists read by the unstructured-grid reader
// with the tissue's cells and a displacement that is zero at rest and not later; the recording and
// the summary reopen.
#include <gtest/gtest.h>
#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"
#include "tests/support/vtk_fields.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

TEST(Quickstart, MainJobRunsAndItsOutputsOpenInVtkReaders) {
  const fs::path out = fs::temp_directory_path() / ("fetouch_quickstart_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const auto r = run_command("cd " + std::string(FETOUCH_SOURCE_DIR) + " && FETOUCH_PRESET=" + FETOUCH_PRESET +
                             " FETOUCH_REPLAY_OUT=" + out.string() + " scripts/quickstart");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("The replay's outputs are in " + out.string()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fetus_phantom.pvd"), std::string::npos);

  vtkNew<vtkXMLDataParser> parser;
  parser->SetFileName((out / "fetus_phantom.pvd").c_str());
  ASSERT_EQ(parser->Parse(), 1);
  vtkXMLDataElement* collection = parser->GetRootElement()->FindNestedElementWithName("Collection");
  ASSERT_NE(collection, nullptr);
  const int datasets = collection->GetNumberOfNestedElements();
  EXPECT_GE(datasets, 6);  // at rest and every 10 frames of the 3 s poke
  vtkIdType cells = -1;
  double previous_time = -1, largest = 0;
  for (int i = 0; i < datasets; ++i) {
    vtkXMLDataElement* d = collection->GetNestedElement(i);
    const double time = std::stod(d->GetAttribute("timestep"));
    EXPECT_GT(time, previous_time);
    previous_time = time;
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName((out / d->GetAttribute("file")).c_str());
    reader->Update();
    vtkUnstructuredGrid* grid = reader->GetOutput();
    ASSERT_GT(grid->GetNumberOfCells(), 1000) << d->GetAttribute("file");
    if (cells >= 0) {
      EXPECT_EQ(grid->GetNumberOfCells(), cells);
    }
    cells = grid->GetNumberOfCells();
    const double most = largest_point_vector(grid);
    ASSERT_GE(most, 0) << "no displacement field";
    if (i == 0) {
      EXPECT_EQ(most, 0) << "at rest";
    }
    largest = std::max(largest, most);
  }
  EXPECT_GT(largest, 0.004);  // the poke presses 8 mm

  const app::Recording recording = app::read_recording(out / "recording.h5");
  EXPECT_EQ(recording.devices.at(0).samples.size(), 3001u);
  const YAML::Node summary = YAML::LoadFile((out / "summary.json").string());
  EXPECT_EQ(summary["ticks"].as<long>(), 3001);
  EXPECT_EQ(summary["newton_failures"].as<long>(), 0);
  fs::remove_all(out);
}

}  // namespace
}  // namespace fetouch::testing
