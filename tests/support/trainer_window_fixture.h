// The trainer window's in-process tests' common ground (label gui, under Xvfb): one QApplication for
// the process, the shipped scenes by name, and a fixture that skips without a display and gives
// each test a scratch folder.
#pragma once

#include <gtest/gtest.h>
#include <QApplication>
#include <QSurfaceFormat>
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
