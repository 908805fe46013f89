// The trainer window's controls driven by QTest (label gui, under Xvfb): pause stops simulated
// time (the tick count does not grow), reset returns the tissue to rest (displacement 0 in the
// snapshot), record writes a take that `fetouch replay` accepts and its anatomy beside it, which
// reads back as the session's mesh (its outer surface found again from the tetrahedra alone) and
// which the review window opens and scrubs, switching the local model and
// hold with the keys is applied with robust gains or refused with the reason on screen, and keys
// move the mouse probe's cursor into the tissue so that its force rises with depth.
#include <gtest/gtest.h>
#include <unistd.h>
#include <QApplication>
#include <QImage>
#include <QMouseEvent>
#include <QSurfaceFormat>
#include <QTest>
#include <QVTKOpenGLStereoWidget.h>
#include <QVTKOpenGLWindow.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <set>
#include <sstream>

#include "app/recording.h"
#include "app/scene_mesh.h"
#include "app/trainer/review_window.h"
#include "app/trainer/tissue_view.h"
#include "app/trainer/trainer_window.h"
#include "meshes/interface_quality.h"
#include "imaging/phantom.h"
#include "tests/support/run_command.h"
#include "tests/support/test_paths.h"
#include "tests/support/trainer_window_fixture.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;
using app::trainer::TrainerWindow;

double largest_displacement(const TrainerWindow& w) {
  double largest = 0;
  const auto& u = w.shown().displacement;
  for (std::size_t i = 0; i + 2 < u.size(); i += 3) largest = std::max(largest, double(std::hypot(u[i], u[i + 1], u[i + 2])));
  return largest;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::size_t(q * double(v.size() - 1) + 0.5)];
}

TEST_F(TrainerWindowTest, InterfacesAreDrawnSmoothRegionByRegionAndEachCanBeHidden) {
  // What the 3D view draws between regions, per region and per region across: the angle between
  // neighbouring drawn triangles' normal lines (meshes/interface_quality.h, on the triangles the
  // view draws), within the mesher's bounds (median <= 10, 99th percentile <= 35 degrees) on both
  // scenes. The conforming scene draws its mesh's interfaces; the default scene's mesh has voted
  // regions, whose interfaces are a staircase of element faces (median over 30 degrees on its
  // largest, measured here on the mesh itself), and draws its label map's smooth surfaces instead,
  // each no farther from the phantom's shapes than a voxel's diagonal.
  app::trainer::WindowOptions options;
  options.out = out_;
  for (const std::string file : {"fetus_phantom_conforming.yaml", "fetus_phantom.yaml"}) {
    SCOPED_TRACE(file);
    const bool conforming = file == "fetus_phantom_conforming.yaml";
    TrainerWindow w(scene(file), {}, options);
    w.show();
    ASSERT_TRUE(w.session());
    app::trainer::TissueView* view = w.view();
    ASSERT_TRUE(view);
    EXPECT_EQ(view->draws_label_surfaces(), !conforming);
    ASSERT_GE(view->regions(), 3u);  // the wall, the head and the body draw what they share with larger regions
    const app::trainer::MeshView& mesh = w.session()->mesh();
    std::map<unsigned int, std::string> region_names = mesh.region_name;
    for (std::size_t i = 0; i < view->regions(); ++i) {
      const auto& points = view->region_points(i);
      const auto& drawn = view->region_triangles(i);
      const auto& across = view->region_across(i);
      ASSERT_EQ(drawn.size(), across.size());
      vtkPolyData* data = view->drawn_region(i);
      ASSERT_TRUE(data);
      EXPECT_EQ(data->GetNumberOfPolys(), static_cast<vtkIdType>(drawn.size()));
      EXPECT_TRUE(data->GetPointData()->GetNormals()) << "shaded with point normals";
      std::map<unsigned int, std::vector<std::array<int, 3>>> by_across;
      for (std::size_t t = 0; t < drawn.size(); ++t)
        by_across[across[t]].push_back({int(drawn[t][0]), int(drawn[t][1]), int(drawn[t][2])});
      for (const auto& [other, triangles] : by_across) {
        const std::vector<double> angles = meshes::neighbour_normal_angles_deg(points, triangles);
        SCOPED_TRACE(view->region_name(i) + " against " + region_names[other] + ", " + std::to_string(triangles.size()) + " triangles");
        std::printf("%s: %s against %s, %zu triangles, neighbours' normals %.1f deg median, %.1f deg 99th percentile\n",
                    file.c_str(), view->region_name(i).c_str(), region_names[other].c_str(), triangles.size(),
                    percentile(angles, 0.5), percentile(angles, 0.99));
        if (triangles.size() < 20) continue;  // a patch where the head touches the wall
        EXPECT_LE(percentile(angles, 0.5), 10);
        EXPECT_LE(percentile(angles, 0.99), 35);
      }
    }
    if (!conforming) {
      // The mesh's own interfaces: faces two elements of different regions share.
      std::map<std::array<unsigned int, 3>, std::size_t> holder;
      std::map<std::pair<unsigned int, unsigned int>, std::vector<std::array<int, 3>>> faces;
      static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
      for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
        for (const auto& f : kFace) {
          std::array<unsigned int, 3> key{mesh.tetrahedra[t][f[0]], mesh.tetrahedra[t][f[1]], mesh.tetrahedra[t][f[2]]};
          std::sort(key.begin(), key.end());
          const auto [at, fresh] = holder.emplace(key, t);
          if (fresh || mesh.material[at->second] == mesh.material[t]) continue;
          const auto pair = std::minmax(mesh.material[at->second], mesh.material[t]);
          faces[pair].push_back({int(key[0]), int(key[1]), int(key[2])});
        }
      std::size_t largest = 0;
      double largest_median = 0;
      for (const auto& [pair, list] : faces)
        if (list.size() > largest)
          largest = list.size(), largest_median = percentile(meshes::neighbour_normal_angles_deg(mesh.points, list), 0.5);
      std::size_t all = 0;
      for (const auto& [pair, list] : faces) all += list.size();
      std::printf("the mesh's own interfaces: %zu faces, the largest interface's median %.1f deg\n", all, largest_median);
      EXPECT_GT(largest_median, 30) << "the voted regions' interfaces are a staircase";
      // The drawn surfaces at rest against the phantom's own shapes: a point of region R's surface
      // has R within a voxel's diagonal of it and another label within the same distance.
      const config::Scene s = scene(file);
      const imaging::PhantomGeometry shapes = imaging::phantom_geometry(app::phantom_settings(s.mesh.phantom));
      std::map<std::string, std::vector<int>> labels_of(s.mesh.meshing.regions.begin(), s.mesh.meshing.regions.end());
      const double reach = std::sqrt(3.0);  // mm
      long points = 0, off = 0;
      for (std::size_t i = 0; i < view->regions(); ++i) {
        const std::vector<int>& mine = labels_of[view->region_name(i)];
        for (const auto& x : view->region_points(i)) {
          bool in = false, out = false;
          for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dz = -1; dz <= 1; ++dz) {
                const int l = shapes.label_at({1e3 * x[0] + dx, 1e3 * x[1] + dy, 1e3 * x[2] + dz});
                (std::find(mine.begin(), mine.end(), l) != mine.end() ? in : out) = true;
              }
          ++points, off += !(in && out);
        }
      }
      std::printf("%ld of %ld drawn points have their region and another within %.2f mm\n", points - off, points, reach);
      EXPECT_LE(off, points / 100) << "at most 1 % of the drawn points farther than a voxel's diagonal from their interface";
    }

    // Each region's toggle hides its surfaces and shows them again; an unknown name is refused.
    // The screenshot shows the view as it is at once: taken just before and just after a region is
    // hidden, with no event between, the 3D view's pixels differ (the view is a window of its own,
    // whose frame the screenshot reads back from VTK, not what Qt last painted).
    const fs::path shown_png = out_ / ("shown-" + file + ".png"), hidden_png = out_ / ("hidden-" + file + ".png");
    auto* widget = w.findChild<QVTKOpenGLStereoWidget*>();
    ASSERT_TRUE(widget && QTest::qWaitForWindowExposed(widget->embeddedOpenGLWindow()));
    QTest::qWait(300);
    EXPECT_TRUE(w.save_screenshot(shown_png));
    const std::string name = view->region_name(0);
    EXPECT_TRUE(w.set_region_visible(name, false));
    EXPECT_FALSE(view->region_visible(0));
    EXPECT_TRUE(view->region_visible(1));
    EXPECT_TRUE(w.save_screenshot(hidden_png));
    {
      const QImage before(QString::fromStdString(shown_png.string())), after(QString::fromStdString(hidden_png.string()));
      ASSERT_TRUE(!before.isNull() && before.size() == after.size());
      const QRect area(widget->mapTo(&w, QPoint(0, 0)), widget->size());
      long differ = 0;
      for (int y = area.top(); y <= area.bottom(); ++y)
        for (int x = area.left(); x <= area.right(); ++x) {
          const QRgb a = before.pixel(x, y), b = after.pixel(x, y);
          differ += std::abs(qRed(a) - qRed(b)) + std::abs(qGreen(a) - qGreen(b)) + std::abs(qBlue(a) - qBlue(b)) > 30;
        }
      std::printf("hiding %s changed %ld of the 3D view's %d pixels\n", name.c_str(), differ, area.width() * area.height());
      EXPECT_GT(differ, 500) << "the second screenshot shows " << name << " hidden";
    }
    EXPECT_TRUE(w.set_region_visible(name, true));
    EXPECT_TRUE(view->region_visible(0));
    EXPECT_FALSE(w.set_region_visible("no such region", false));
  }
}

TEST_F(TrainerWindowTest, PauseStopsTimeResetReturnsToRestRecordReplays) {
  app::trainer::WindowOptions options;
  options.out = out_;
  TrainerWindow w(scene("fetus_simple.yaml"), {}, options);
  w.show();
  QApplication::setActiveWindow(&w);  // shortcuts go to the active window (Xvfb has no window manager)
  ASSERT_TRUE(w.session());
  // Into the poke's hold (8 mm deep from 1.1 s to 2.1 s of the session's time): waited for on the
  // session's clock, not the wall's, since a loaded machine starts the session late; the shown
  // tissue may trail the probe by a frame or two.
  wait_for_session_ticks(w, 1700);
  const auto ticks = [&w] { return w.session()->monitor().ticks.load(); };
  for (int waited = 0; waited < 5000 && ticks() < 2100 && largest_displacement(w) <= 2e-3; waited += 20) QTest::qWait(20);
  EXPECT_GT(largest_displacement(w), 2e-3) << "mid-press, the tissue should be pushed in (tick " << ticks() << ")";
  QTest::keyClick(&w, Qt::Key_Space);
  QTest::qWait(200);
  const long paused_at = w.session()->monitor().ticks.load();
  QTest::qWait(700);
  EXPECT_EQ(w.session()->monitor().ticks.load(), paused_at) << "paused: no tick runs";
  EXPECT_TRUE(w.session()->paused());
  QTest::keyClick(&w, Qt::Key_Space);
  EXPECT_GT(wait_for_session_ticks(w, paused_at + 101, 5000), paused_at + 100) << "resumed";
  // Reset: a new take from rest.
  QTest::keyClick(&w, Qt::Key_R);
  EXPECT_EQ(largest_displacement(w), 0.0) << "after a reset the tissue is at rest";
  EXPECT_LT(w.session()->monitor().ticks.load(), 200);
  // Record a take, stop it, and replay it with the real binary.
  QTest::keyClick(&w, Qt::Key_R, Qt::ControlModifier);
  ASSERT_TRUE(w.recording());
  const fs::path take = *w.recording();
  QTest::qWait(1500);
  QTest::keyClick(&w, Qt::Key_R, Qt::ControlModifier);
  EXPECT_FALSE(w.recording());
  ASSERT_TRUE(fs::exists(take));
  const auto replay = run_command(fetouch("replay " + (fs::path(FETOUCH_SOURCE_DIR) / "config/scenes/fetus_simple.yaml").string() +
                                          " --trajectory " + take.string() + " --mesh-every 0 --out " + (out_ / "replayed").string()));
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  // Its anatomy: the session's mesh, read back.
  const fs::path anatomy = out_ / (take.stem().string() + ".anatomy.vtu");
  ASSERT_TRUE(fs::exists(anatomy));
  const app::trainer::ReviewTake review = app::trainer::load_review_take(out_, take.filename());
  const app::trainer::MeshView& mesh = w.session()->mesh();
  EXPECT_EQ(review.anatomy_file, anatomy);
  EXPECT_EQ(review.anatomy.points.size(), mesh.points.size());
  EXPECT_EQ(review.anatomy.tetrahedra, mesh.tetrahedra);
  EXPECT_EQ(review.anatomy.material, mesh.material);
  EXPECT_EQ(review.anatomy.region_name, mesh.region_name);
  // The solver's boundary faces against those no second tetrahedron shares.
  ASSERT_EQ(review.anatomy.boundary_triangles.size(), mesh.boundary_triangles.size());
  std::set<std::array<unsigned int, 3>> solver_faces, read_faces;
  for (auto f : mesh.boundary_triangles) std::sort(f.begin(), f.end()), solver_faces.insert(f);
  for (auto f : review.anatomy.boundary_triangles) std::sort(f.begin(), f.end()), read_faces.insert(f);
  EXPECT_EQ(read_faces, solver_faces);
  EXPECT_FALSE(review.scores);
  EXPECT_GT(review.duration_s, 1.0);
  app::trainer::ReviewWindow r(review, {});
  r.show();
  EXPECT_DOUBLE_EQ(r.time_shown(), review.duration_s);  // the take's end first
  r.show_time(0.5);
  EXPECT_DOUBLE_EQ(r.time_shown(), 0.5);
  r.show_time(1e6);
  EXPECT_DOUBLE_EQ(r.time_shown(), review.duration_s);
  EXPECT_EQ(r.maneuver_at(0.5), -1);  // not an exercise
}

// What the hand feels, said in the window: on the default-like anatomy the status line shows the
// stiffness identified from the probe's own signals beside the frame's condensed one while it
// presses; on the stiff block under the light grip (stiff_block_grip.yaml) the passivity
// layer scales the probe and the status line says so, while the energy plot runs beside the others.
TEST_F(TrainerWindowTest, TheStatusLineSaysWhatTheHandFeelsAndWhenThePassivityLayerActs) {
  // The status line once it shows `text` (waiting up to `ms`), or "" if it never does.
  const auto wait_for = [](TrainerWindow& w, const std::string& text, int ms) {
    for (int waited = 0; waited < ms; waited += 50) {
      const std::string status = w.status();
      if (status.find(text) != std::string::npos) return status;
      QTest::qWait(50);
    }
    return std::string();
  };
  app::trainer::WindowOptions options;
  options.out = out_;
  {
    TrainerWindow w(scene("fetus_simple.yaml"), {}, options);
    w.show();
    ASSERT_TRUE(w.session());
    const std::string status = wait_for(w, " felt ", 3000);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(status, m, std::regex("felt (\\d+) / tissue (\\d+) N/m"))) << w.status();
    const double felt = std::stod(m[1]), tissue = std::stod(m[2]);
    EXPECT_GT(tissue, 0);
    EXPECT_NEAR(felt, tissue, 0.5 * tissue);  // mid-press, through the real-time loop
  }
  {
    TrainerWindow w(scene("stiff_block_grip.yaml"), {}, options);
    w.show();
    ASSERT_TRUE(w.session());
    EXPECT_NE(wait_for(w, "PASSIVITY: ", 3000), "") << w.status();
  }
}

// The displacement along -n of the patch at `patch` under a force f along -n, by `fetouch solve`.
double static_depth(const fs::path& scene, const Eigen::Vector3d& patch, const Eigen::Vector3d& n, double f, const fs::path& out) {
  char press[300];
  std::snprintf(press, sizeof press, " --press %.17g %.17g %.17g %.17g %.17g %.17g", patch.x(), patch.y(), patch.z(),
                -f * n.x(), -f * n.y(), -f * n.z());
  const auto s = run_command(fetouch("solve --json --out " + out.string() + " " + scene.string() + press));
  EXPECT_EQ(s.exit_code, 0) << s.err;
  const YAML::Node u = YAML::Load(s.out)["probes"][0]["displacement_m"];
  return -(u[0].as<double>() * n.x() + u[1].as<double>() * n.y() + u[2].as<double>() * n.z());
}

// The mouse probe in a recorded take: the cursor pushed 4 mm, then 8 mm, below the surface and held.
// The force rises with depth, and once settled it is what a static `fetouch solve` needs to hold the
// patch at the depth the recording shows (within 10 %): the static force for that depth is found by
// two solves (the held force, then the secant's next guess) and interpolated between them.
TEST_F(TrainerWindowTest, TheMouseProbeFollowsTheCursorIntoTheTissue) {
  const std::unique_ptr<TrainerWindow> window = mouse_window("fetus_simple.yaml");
  TrainerWindow& w = *window;
  w.toggle_recording();  // a take from rest, recorded
  ASSERT_TRUE(w.session() && w.session()->cursor() && w.recording());
  const fs::path take = *w.recording();
  QTest::qWait(300);
  ASSERT_FALSE(w.shown().patch_centre.empty());
  const Eigen::Vector3d patch = w.shown().patch_centre[0], n = w.shown().patch_normal[0];  // at rest; n outward
  const auto force = [&w] { return w.session()->monitor().force_n[0].load(); };
  EXPECT_LT(force(), 1e-6) << "the cursor starts 1 cm above the tissue";
  // Push the cursor down (the probe's patch normal points up here) 14 mm, then 4 mm more.
  w.set_cursor(w.cursor() - Eigen::Vector3d(0, 0, 0.014));
  QTest::qWait(1500);
  const double shallow = force();
  w.set_cursor(w.cursor() - Eigen::Vector3d(0, 0, 0.004));
  QTest::qWait(2000);
  const double deep = force();
  w.toggle_recording();  // ends the take (and starts an unrecorded one)
  std::printf("force with the cursor 4 mm and 8 mm below the surface: %.3f N, %.3f N\n", shallow, deep);
  EXPECT_GT(shallow, 0.01);
  EXPECT_GT(deep, shallow * 1.2) << "the force rises with depth";

  // Settled: 0.3 s before the stop's 0.2 s ramp-out at the end of the take.
  const app::Recording recording = app::read_recording(take);
  const auto& samples = recording.devices.at(0).samples;
  ASSERT_GT(samples.size(), 1000u);
  double held_force = 0, depth = 0, lowest = 1e300, highest = 0;
  const std::size_t last = 300, end = samples.size() - 300;
  for (std::size_t k = end - last; k < end; ++k) {
    held_force += samples[k].normal_force / last;
    depth += -(samples[k].position - patch).dot(n) / last;
    lowest = std::min(lowest, samples[k].normal_force), highest = std::max(highest, samples[k].normal_force);
  }
  EXPECT_LT(highest - lowest, 0.02 * held_force) << "settled";
  const fs::path scene_file = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml";
  const double d1 = static_depth(scene_file, patch, n, held_force, out_ / "solve1");
  const double f2 = held_force * depth / d1;
  const double d2 = static_depth(scene_file, patch, n, f2, out_ / "solve2");
  const double needed = held_force + (f2 - held_force) * (depth - d1) / (d2 - d1);
  std::printf("held %.2f mm deep with %.4f N; fetouch solve: %.2f mm under %.4f N, %.2f mm under %.4f N: %.4f N needed (%+.1f %%)\n",
              1e3 * depth, held_force, 1e3 * d1, held_force, 1e3 * d2, f2, needed, 100 * (held_force / needed - 1));
  EXPECT_GT(depth, 5e-3);
  EXPECT_NEAR(held_force / needed, 1, 0.10);
}

// The 3D view is a window of its own inside the trainer's (it renders straight to the screen, not
// through Qt's composition: docs/trainer.md). Keys typed while it has the focus still reach the
// window: the shortcuts (space pauses) and the view's own keys (] pushes the mouse probe's cursor
// 1 mm along the view, away from the eye); so does the mouse (shift+move moves the cursor).
TEST_F(TrainerWindowTest, KeysAndTheMouseInThe3DViewReachTheWindow) {
  const std::unique_ptr<TrainerWindow> window = mouse_window("fetus_simple.yaml");
  TrainerWindow& w = *window;
  ASSERT_TRUE(w.session() && w.session()->cursor());
  auto* view = w.findChild<QVTKOpenGLStereoWidget*>();
  ASSERT_NE(view, nullptr);
  QWindow* embedded = view->embeddedOpenGLWindow();
  ASSERT_TRUE(QTest::qWaitForWindowExposed(embedded));
  QTest::mouseClick(embedded, Qt::LeftButton, Qt::NoModifier, QPoint(view->width() / 2, view->height() / 2));
  QTest::qWait(300);
  const Eigen::Vector3d before = w.cursor();
  QTest::keyClick(embedded, Qt::Key_BracketRight);
  EXPECT_NEAR((w.cursor() - before).norm(), 1e-3, 1e-9) << "] in the view moves the cursor 1 mm";
  // Shift+move in the view moves the cursor in the view plane: to a point 50 px left of the middle,
  // 50 px right, and back (the same point again, 100 px of the view apart from the other).
  const auto shift_move = [&](int dx) {
    const QPointF at(view->width() / 2 + dx, view->height() / 2);
    QMouseEvent move(QEvent::MouseMove, at, at, view->mapToGlobal(at.toPoint()), Qt::NoButton, Qt::NoButton, Qt::ShiftModifier);
    QApplication::sendEvent(embedded, &move);
    return w.cursor();
  };
  const Eigen::Vector3d left = shift_move(-50), right = shift_move(50), again = shift_move(-50);
  EXPECT_GT((right - left).norm(), 1e-3) << "shift+move in the view moves the cursor";
  EXPECT_LT((again - left).norm(), 1e-9) << "the same pixel, the same place";
  QTest::keyClick(embedded, Qt::Key_Space);
  QTest::qWait(200);
  EXPECT_TRUE(w.session()->paused()) << "space in the view pauses";
  const long paused_at = w.session()->monitor().ticks.load();
  QTest::qWait(300);
  EXPECT_EQ(w.session()->monitor().ticks.load(), paused_at);
}

// M and H ask for the next local model and the other hold. On the default scene (gains chosen
// robustly every frame) P + FOH is accepted, and the window then shows it and renders with gains
// the analysis accepted (margin > 0 in the next frames). With the scene's gains fixed at Kh = 1000
// N/m and N I = 100 N/m, which PI + Smith renders robustly stable on any stiffness of 10 to 300 N/m
// (spectral radius 0.91 to 0.93, tests/haptics/test_mode_switch.cc checks the like) and plain PI
// does not (radius 1.2 to 133), asking for PI is refused, and the message line says why.
TEST_F(TrainerWindowTest, SwitchingTheLocalModelIsAppliedOrRefusedWithTheReason) {
  app::trainer::WindowOptions options;
  options.out = out_;
  {
    TrainerWindow w(scene("fetus_simple.yaml"), {}, options);
    w.show();
    QApplication::setActiveWindow(&w);
    ASSERT_EQ(w.local_model(), haptics::LocalModelKind::pi_smith);
    w.toggle_recording();  // the switch happens in a recorded take
    ASSERT_TRUE(w.recording());
    const fs::path take = *w.recording();
    QTest::qWait(500);
    QTest::keyClick(&w, Qt::Key_M);  // pi_smith -> p
    QTest::keyClick(&w, Qt::Key_H);  // zoh -> foh
    QTest::qWait(1200);
    EXPECT_EQ(w.local_model(), haptics::LocalModelKind::p) << w.message();
    EXPECT_EQ(w.hold(), haptics::HoldKind::foh) << w.message();
    const std::string message = w.message();
    const std::size_t from = message.find("p + foh from frame");
    ASSERT_NE(from, std::string::npos) << message;
    const long switched = std::stol(message.substr(from + std::strlen("p + foh from frame")));
    QTest::qWait(500);
    EXPECT_GT(w.shown().stability_margin, 0);
    w.toggle_recording();  // ends the take
    // The recording's frames carry the mode their answers were made for: the scene's, then from the
    // frame whose answer the analysis accepted (applied from the next, the one the message names)
    // the new one.
    const app::Recording r = app::read_recording(take);
    long first_p = -1, old_rows = 0, old_mode = 0, new_mode = 0;
    for (const app::FrameRecord& f : r.frames) {
      if (f.frame < switched - 1) {
        ++old_rows;
        old_mode += f.local_model == static_cast<int>(haptics::LocalModelKind::pi_smith) && f.hold == static_cast<int>(haptics::HoldKind::zoh);
      } else {
        new_mode += f.local_model == static_cast<int>(haptics::LocalModelKind::p) && f.hold == static_cast<int>(haptics::HoldKind::foh);
        if (first_p < 0) first_p = f.frame;
      }
    }
    EXPECT_EQ(old_mode, old_rows) << "every frame before the switch in the scene's pi_smith + zoh";
    EXPECT_EQ(new_mode, static_cast<long>(r.frames.size()) - old_rows) << "every frame from it on in p + foh";
    EXPECT_GT(new_mode, 5);
    EXPECT_EQ(first_p, switched - 1);
  }
  // The default scene with its gains fixed.
  std::ifstream in(fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "fetus_simple.yaml");
  std::stringstream text;
  text << in.rdbuf();
  const fs::path scenes = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes";
  const std::string fixed = std::regex_replace(
      std::regex_replace(text.str(), std::regex("gains: auto"), "gains: {proportional_n_per_m: 1000, integral_n_per_m: 2}"),
      std::regex("trajectories/"), (scenes / "trajectories").string() + "/");
  ASSERT_NE(fixed, text.str());
  fs::create_directories(out_);
  const fs::path file = out_ / "fixed_gains.yaml";
  std::ofstream(file) << fixed;
  std::optional<config::Scene> s = app::load_scene_or_report(file.string());
  ASSERT_TRUE(s);
  TrainerWindow w(*s, {}, options);
  w.show();
  QApplication::setActiveWindow(&w);
  QTest::qWait(500);
  w.ask_mode(haptics::LocalModelKind::pi, haptics::HoldKind::zoh);
  QTest::qWait(1200);
  EXPECT_EQ(w.local_model(), haptics::LocalModelKind::pi_smith);
  EXPECT_NE(w.message().find("refused pi + zoh: the scene's gains"), std::string::npos) << w.message();
  EXPECT_NE(w.message().find("pi_smith + zoh stays"), std::string::npos) << w.message();
  std::printf("%s\n", w.message().c_str());
}

// Open: a scene with an error is refused with its file, line and reason on the message line and
// the running session goes on; a good one replaces it (another mesh, the title, a take from rest).
TEST_F(TrainerWindowTest, OpenRefusesABrokenSceneAndKeepsTheSessionThenOpensAnother) {
  app::trainer::WindowOptions options;
  options.out = out_;
  TrainerWindow w(scene("fetus_simple.yaml"), {}, options);
  w.show();
  QApplication::setActiveWindow(&w);
  QTest::qWait(600);
  ASSERT_TRUE(w.session());
  const auto* before = w.session();
  const std::size_t points = w.session()->mesh().points.size();
  const long ticks = w.session()->monitor().ticks.load();
  fs::create_directories(out_);
  const fs::path broken = out_ / "broken.yaml";
  std::ofstream(broken) << "name: broken\nunits: SI\nmesh:\n  box: {size_m: [0.1, 0.1, -0.05]}\n";
  EXPECT_FALSE(w.open_scene(broken));
  EXPECT_NE(w.message().find("cannot open " + broken.string()), std::string::npos) << w.message();
  EXPECT_NE(w.message().find("broken.yaml:"), std::string::npos) << "file:line in " << w.message();
  EXPECT_EQ(w.session(), before);
  EXPECT_GT(wait_for_session_ticks(w, ticks + 101, 5000), ticks + 100) << "the session goes on";

  ASSERT_TRUE(w.open_scene(fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "block_press.yaml"));
  EXPECT_EQ(w.windowTitle().toStdString(), "Fetouch trainer: block_press");
  EXPECT_NE(w.session()->mesh().points.size(), points);
  EXPECT_EQ(largest_displacement(w), 0.0) << "a new take from rest";
  EXPECT_GT(wait_for_session_ticks(w, 501), 500);
}

}  // namespace
}  // namespace fetouch::testing

