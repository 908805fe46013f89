// `fetouch render`, the real binary drawing under Xvfb: a mesh it just made and a volume's slice,
// decoded again with VTK's PNG reader. The mesh picture must show the tissue's colour over a white
// background on a fair share of the picture; the slice picture, the phantom's bright uterine wall
// and its dark fluid. Label gui (ctest runs under xvfb-run).
#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkDataArray.h>

#include <cstdlib>
#include <filesystem>

#include "tests/support/run_command.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Picture {
  int width = 0, height = 0;
  double white = 0, tissue = 0, dark = 0;  // shares of pixels
};

Picture look_at(const fs::path& png) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(png.string().c_str());
  reader->Update();
  Picture p;
  int dims[3];
  reader->GetOutput()->GetDimensions(dims);
  p.width = dims[0], p.height = dims[1];
  vtkDataArray* rgb = reader->GetOutput()->GetPointData()->GetScalars();
  const double n = double(rgb->GetNumberOfTuples());
  for (vtkIdType i = 0; i < rgb->GetNumberOfTuples(); ++i) {
    const double r = rgb->GetComponent(i, 0), g = rgb->GetComponent(i, 1), b = rgb->GetComponent(i, 2);
    if (r > 250 && g > 250 && b > 250) p.white += 1 / n;
    if (r > g + 30 && r > b + 30) p.tissue += 1 / n;  // the mesh's salmon, shaded
    if (r < 30 && g < 30 && b < 30) p.dark += 1 / n;
  }
  return p;
}

TEST(RenderCommand, MeshAndSliceArePictured) {
  ASSERT_TRUE(std::getenv("DISPLAY")) << "this test draws with VTK: run it under xvfb-run -a (scripts/quickstart test does)";
  const fs::path dir = fs::temp_directory_path() / ("fetouch_render_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  ASSERT_EQ(run_command(fetouch("phantom --spacing 2 --out " + (dir / "ph").string())).exit_code, 0);
  ASSERT_EQ(run_command(fetouch("mesh " + (dir / "ph" / "phantom_labels.mha").string() + " --labels 3 4 5 6 --size 5 --out " +
                                (dir / "fetus.vtu").string()))
                .exit_code,
            0);
  const auto mesh = run_command(fetouch("render " + (dir / "fetus.vtu").string() + " --width 640 --height 480 --out " +
                                        (dir / "fetus.png").string()));
  ASSERT_EQ(mesh.exit_code, 0) << mesh.err;
  const Picture m = look_at(dir / "fetus.png");
  EXPECT_EQ(m.width, 640);
  EXPECT_EQ(m.height, 480);
  EXPECT_GT(m.tissue, 0.05);
  EXPECT_GT(m.white, 0.3);

  const auto slice = run_command(fetouch("render " + (dir / "ph" / "phantom.mha").string() + " --out " + (dir / "slice.png").string()));
  ASSERT_EQ(slice.exit_code, 0) << slice.err;
  const Picture s = look_at(dir / "slice.png");
  EXPECT_GT(s.dark, 0.1);   // the amniotic fluid
  EXPECT_LT(s.tissue, 0.01);  // grey levels only

  // Not a picture name, not a file.
  EXPECT_EQ(run_command(fetouch("render " + (dir / "fetus.vtu").string() + " --out x.jpg")).exit_code, 2);
  EXPECT_NE(run_command(fetouch("render " + (dir / "missing.vtu").string())).exit_code, 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::testing
