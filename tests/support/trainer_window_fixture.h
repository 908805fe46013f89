// The trainer window's in-process tests' common ground (label gui, under Xvfb): one QApplication for
// the process, the shipped scenes by name, and a fixture that skips without a display and gives
// each test a scratch folder.
#pragma once

#include <gtest/gtest.h>
#include <QApplication>
#include <QSurfaceFormat>
#include <QTest>
#include <QVTKOpenGLNativeWidget.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "app/scene_mesh.h"
#include "app/trainer/trainer_window.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {

inline QApplication& application() {
  static int argc = 1;
  static char name[] = "trainer_window_tests";
  static char* argv[] = {name, nullptr};
  // Never destroyed: the process ends without tearing Qt down after MPI has finalised.
  static QApplication* app = nullptr;
  if (!app) {
    QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
    app = new QApplication(argc, argv);
  }
  return *app;
}

inline config::Scene scene(const std::string& file) {
  std::optional<config::Scene> s = app::load_scene_or_report((std::filesystem::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / file).string());
  EXPECT_TRUE(s);
  return *s;
}

// Waits, with Qt's events processed, until the window's session has run `ticks` haptic ticks or
// `limit_ms` of wall time have passed, and returns the ticks reached. Tests that need session time
// wait on the session's clock, not the wall's: a loaded machine starts the session late and runs it
// slower than real time (a wall-clock second once recorded 0.467 s of take).
inline long wait_for_session_ticks(app::trainer::TrainerWindow& w, long ticks, int limit_ms = 15000) {
  const auto reached = [&w] { return w.session()->monitor().ticks.load(); };
  for (int waited = 0; waited < limit_ms && reached() < ticks; waited += 20) QTest::qWait(20);
  return reached();
}

class TrainerWindowTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no display: run under xvfb-run -a";
    application();
    scratch_.emplace("fetouch_trainer_window");  // the takes go with a passed test
    out_ = scratch_->path();
  }
  // A window on a shipped scene with the mouse driving its first probe, its takes in out_, shown
  // and made the active window (shortcuts go to it; Xvfb has no window manager).
  std::unique_ptr<app::trainer::TrainerWindow> mouse_window(const std::string& file) {
    app::trainer::TrainerOptions session;
    session.mouse = true;
    app::trainer::WindowOptions options;
    options.out = out_;
    auto w = std::make_unique<app::trainer::TrainerWindow>(scene(file), session, options);
    w->show();
    QApplication::setActiveWindow(w.get());
    return w;
  }
  std::optional<ScratchDir> scratch_;
  std::filesystem::path out_;
};

}  // namespace fetouch::testing
