// The trainer window's exercise, in-process (label gui, under Xvfb): two hands on one mouse, each
// holding where the mouse left it, and an answered exercise opening its take in the review window.
#include <gtest/gtest.h>
#include <QApplication>
#include <QTest>

#include <cstdio>
#include <functional>
#include <string>

#include "app/trainer/review_window.h"
#include "app/trainer/trainer_window.h"
#include "tests/support/trainer_window_fixture.h"

namespace fetouch::testing {
namespace {

using app::trainer::TrainerWindow;

// Two hands and one mouse (leopold.yaml's two PHANTOMs absent): the mouse drives the left hand;
// pressed in, it holds there while Tab gives the mouse the right hand, which presses in beside it;
// Tab again comes back to the left hand's cursor where it was left.
TEST_F(TrainerWindowTest, TheMouseDrivesEitherHandAndTheOtherHoldsWhereItWasLeft) {
  app::trainer::WindowOptions options;
  options.out = out_;
  TrainerWindow w(scene("leopold.yaml"), {}, options);
  w.show();
  QApplication::setActiveWindow(&w);
  ASSERT_TRUE(w.session() && w.session()->cursor());
  if (w.session()->mouse_probes() != 2) GTEST_SKIP() << "a PHANTOM was found: the mouse drives " << w.session()->mouse_probes() << " hands";
  EXPECT_EQ(w.session()->cursor_probe(), 0);
  const auto force = [&w](int p) { return w.session()->monitor().force_n[p].load(); };
  const auto wait_until = [](const std::function<bool()>& done, int ms) {
    for (int waited = 0; waited < ms && !done(); waited += 20) QTest::qWait(20);
    return done();
  };
  // The left hand 15 mm in from 1 cm out.
  w.set_cursor(w.cursor() - 0.025 * w.shown().patch_normal[0]);
  ASSERT_TRUE(wait_until([&] { return force(0) > 0.2; }, 15000)) << "left hand: " << force(0) << " N";
  QTest::qWait(500);
  const Eigen::Vector3d left_cursor = w.cursor();
  const double left_force = force(0);
  const auto left_hand = [&w] { return Eigen::Vector3d(w.session()->monitor().probes.front()[0].position); };
  w.session()->monitor().probes.take();
  const Eigen::Vector3d left_at = left_hand();
  EXPECT_LT(force(1), 1e-6) << "the right hand waits above the tissue";
  QTest::keyClick(&w, Qt::Key_Tab);
  ASSERT_EQ(w.session()->cursor_probe(), 1);
  EXPECT_NE(w.message().find("the mouse drives right"), std::string::npos) << w.message();
  w.set_cursor(w.cursor() - 0.025 * w.shown().patch_normal[1]);
  ASSERT_TRUE(wait_until([&] { return force(1) > 0.2; }, 15000)) << "right hand: " << force(1) << " N";
  QTest::qWait(500);
  // A frame of two contacts' onset can pass the force watchdog's 0.25 s on a busy machine, which
  // fades the forces out until the next frame: the left hand's force is looked for over 3 s.
  wait_until([&] { return force(0) > 0.1; }, 3000);
  w.session()->monitor().probes.take();
  const double moved = (left_hand() - left_at).norm();
  std::printf("left hand %.3f N alone, %.3f N (moved %.2f mm) with the right one pressing %.3f N beside it\n", left_force,
              force(0), 1e3 * moved, force(1));
  // The left hand holds its press: still in (the right's press pulls the surface under it down, so
  // its force falls by as much as its share of the wall), and where it was: its spring (200 N/m)
  // moves it half a millimetre for the 0.1 N it loses, 3 mm allowed for the tissue still settling
  // (against the 25 mm each cursor went in).
  EXPECT_GT(force(0), 0.1) << "the left hand still presses";
  EXPECT_LT(moved, 3e-3) << "the left hand stays where it was left";
  QTest::keyClick(&w, Qt::Key_Tab);
  EXPECT_EQ(w.session()->cursor_probe(), 0);
  EXPECT_EQ(w.cursor(), left_cursor);
}

// The exercise in the window, answered without palpating (the mouse's hands untouched): the
// assessment scores it (no maneuver reached, nothing covered), and `Review the take` opens the take
// in the review window, with the scores.
TEST_F(TrainerWindowTest, AnAnsweredExerciseOpensItsTakeInTheReviewWindow) {
  app::trainer::WindowOptions options;
  options.out = out_;
  options.exercise.on = true;
  config::Scene s = scene("leopold.yaml");
  s.mesh.phantom.pose = config::draw_pose(1);
  TrainerWindow w(s, {}, options);
  w.show();
  ASSERT_TRUE(w.session());
  EXPECT_EQ(w.open_review(), nullptr) << "nothing to review before the answer";
  // A second of the session's time before the answer.
  ASSERT_GE(wait_for_session_ticks(w, 1000), 1000) << "the session ran less than a second in 15 s of waiting";
  for (int k = 0; k < 4; ++k) ASSERT_TRUE(w.next_maneuver());
  const config::FetalPose pose = config::draw_pose(1);
  ASSERT_TRUE(w.answer({pose.lie, pose.presentation, pose.back})) << w.message();
  ASSERT_TRUE(w.figures().assessment);
  EXPECT_EQ(w.figures().assessment->answer_score(), 3);
  EXPECT_EQ(w.figures().assessment->maneuvers_reached(), 0);
  app::trainer::ReviewWindow* r = w.open_review();
  ASSERT_NE(r, nullptr) << w.message();
  ASSERT_TRUE(r->take().scores);
  EXPECT_EQ(r->take().scores->answer_score(), 3);
  EXPECT_EQ(r->take().recording.devices.size(), 2u);
  EXPECT_GT(r->take().duration_s, 0.5);
  EXPECT_EQ(r->take().anatomy.tetrahedra, w.session()->mesh().tetrahedra);
  // The review draws the regions as the trainer did: the label map's smooth surfaces, made again
  // from the recorded scene (the exercise's fetus in its drawn pose), triangle for triangle.
  ASSERT_TRUE(w.view()->draws_label_surfaces());
  ASSERT_EQ(r->take().smooth.size(), w.view()->regions());
  for (std::size_t i = 0; i < w.view()->regions(); ++i) {
    EXPECT_EQ(r->take().smooth[i].triangles, w.view()->region_triangles(i));
    EXPECT_EQ(r->take().smooth[i].points, w.view()->region_points(i));
  }
}

}  // namespace
}  // namespace fetouch::testing
