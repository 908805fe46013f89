// `fetouch trainer`, the real binary in a real window under Xvfb (label gui): every shipped scene
// opens, runs 3 s with its scripted devices and closes with exit 0 and a screenshot; the 3D view's
// probe region changes between rest and mid-press; another program's load is measured and said;
// without a display the command says to use xvfb-run and exits 2.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <regex>

#include "app/realtime_cores.h"
#include "tests/support/run_command.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/test_paths.h"
#include "tests/support/thread_nice.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;

struct Png {
  int width = 0, height = 0;
  vtkSmartPointer<vtkImageData> image;
};

Png read_png(const fs::path& file) {
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName(file.string().c_str());
  reader->Update();
  Png p;
  p.image = reader->GetOutput();
  int dims[3];
  p.image->GetDimensions(dims);
  p.width = dims[0], p.height = dims[1];
  return p;
}

// The mean absolute difference of two pictures over a box (fractions of width and height, from the
// top left), in grey levels.
double difference(const Png& a, const Png& b, double x0, double x1, double y0, double y1) {
  vtkDataArray* pa = a.image->GetPointData()->GetScalars();
  vtkDataArray* pb = b.image->GetPointData()->GetScalars();
  double sum = 0;
  long n = 0;
  for (int y = static_cast<int>(y0 * a.height); y < static_cast<int>(y1 * a.height); ++y)
    for (int x = static_cast<int>(x0 * a.width); x < static_cast<int>(x1 * a.width); ++x) {
      const vtkIdType i = static_cast<vtkIdType>(a.height - 1 - y) * a.width + x;  // VTK's rows go up
      for (int c = 0; c < 3; ++c) sum += std::abs(pa->GetComponent(i, c) - pb->GetComponent(i, c));
      ++n;
    }
  return n ? sum / (3.0 * n) : 0;
}

TEST(TrainerCommand, EveryShippedSceneOpensRunsAndClosesWithAScreenshot) {
  ASSERT_TRUE(std::getenv("DISPLAY")) << "this test opens windows: run it under xvfb-run -a (scripts/quickstart test does)";
  const ScratchDir scratch("fetouch_trainer_scenes");
  const fs::path& dir = scratch.path();
  int ran = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string name = entry.path().stem().string();
    if (name == "spine_phantom" && !fs::exists(fs::path(FETOUCH_SOURCE_DIR) / ".." / "shared" / "data" / "ultrasound")) {
      std::printf("skipping %s: ../shared/data/ultrasound is not beside the repository\n", name.c_str());
      continue;
    }
    const fs::path shot = dir / (name + ".png");
    const auto r = run_command(fetouch("trainer " + entry.path().string() + " --duration 3 --screenshot " + shot.string() +
                                       " --out " + (dir / name).string() + " --json"));
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    ASSERT_TRUE(fs::exists(shot)) << name;
    const Png png = read_png(shot);
    EXPECT_GE(png.width, 800) << name;
    EXPECT_NE(r.out.find("\"ticks\":3000"), std::string::npos) << name << ": " << r.out;
    ++ran;
  }
  EXPECT_GE(ran, 5);
}

TEST(TrainerCommand, TheProbesRegionChangesBetweenRestAndMidPress) {
  ASSERT_TRUE(std::getenv("DISPLAY")) << "run under xvfb-run -a";
  const ScratchDir scratch("fetouch_trainer_press");
  const fs::path& dir = scratch.path();
  const std::string scene = (fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml").string();
  // The scene's poke reaches the surface at 0.6 s and is 8 mm deep from 1.1 s to 2.1 s.
  const auto rest = run_command(fetouch("trainer " + scene + " --duration 0.3 --screenshot " + (dir / "rest.png").string() +
                                        " --out " + dir.string()));
  const auto press = run_command(fetouch("trainer " + scene + " --duration 1.8 --screenshot " + (dir / "press.png").string() +
                                         " --out " + dir.string()));
  ASSERT_EQ(rest.exit_code, 0) << rest.err;
  ASSERT_EQ(press.exit_code, 0) << press.err;
  const Png a = read_png(dir / "rest.png"), b = read_png(dir / "press.png");
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  // The 3D view fills the left ~2/3 under the tool bar; the probe presses the top of the tissue in
  // its middle. A band under the status bar, left of the colour bar, is where nothing should move.
  const double probe = difference(a, b, 0.25, 0.45, 0.15, 0.45);
  const double corner = difference(a, b, 0.02, 0.10, 0.70, 0.90);
  EXPECT_GT(probe, 3.0) << "the probe's region should change between rest and mid-press";
  EXPECT_LT(corner, 1.0) << "the background should not change";
  // And the ultrasound image (right column, top) shows the press too.
  EXPECT_GT(difference(a, b, 0.70, 0.98, 0.08, 0.55), 1.0);
}

// A number of the --json summary (NaN when absent).
double json_number(const std::string& json, const std::string& key) {
  std::smatch m;
  return std::regex_search(json, m, std::regex("\"" + key + "\":(-?[0-9.eE+-]+)")) ? std::stod(m[1]) : std::nan("");
}

// Another program keeping a core busy for the whole take: the window measures it and says the
// machine is busy (the summary counts the seconds it said so); nothing fails or is skipped for it.
TEST(TrainerCommand, SaysTheMachineIsBusyWhileAnotherProgramKeepsACore) {
  const ScratchDir scratch("fetouch_trainer_busy");
  ASSERT_TRUE(std::getenv("DISPLAY")) << "run under xvfb-run -a";
  const pid_t hog = fork();
  ASSERT_GE(hog, 0);
  if (hog == 0) {
    volatile double x = 0;
    for (;;) x = x + 1;
  }
  const std::string scene = (fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml").string();
  const auto r = run_command(fetouch("trainer " + scene + " --duration 3 --json --out " + scratch.path().string()));
  kill(hog, SIGKILL);
  waitpid(hog, nullptr, 0);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GE(json_number(r.out, "others_cores_max"), 0.5) << r.out;
  EXPECT_GE(json_number(r.out, "busy_s"), 1.0) << r.out;
  EXPECT_EQ(json_number(r.out, "ticks"), 3000) << r.out;
  // Ahead of it where the process may raise a thread's priority (a thread of the test's tries).
  const NiceRights rights = nice_rights(app::kSolverNice);
  EXPECT_EQ(json_number(r.out, "solver_nice"), rights.expected(app::kSolverNice)) << r.out;
  EXPECT_EQ(json_number(r.out, "window_nice"), rights.expected(app::kWindowNice)) << r.out;
}

TEST(TrainerCommand, WithoutADisplayItSaysToUseXvfbAndExits2) {
  const std::string scene = (fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml").string();
  const auto r = run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + fetouch("trainer " + scene + " --duration 1"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("xvfb-run -a"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace fetouch::testing
