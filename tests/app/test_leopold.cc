// The Leopold exercise's assessment (app/exercise/leopold.h) on the phantom's fetus in every pose,
// against answers found independently of it:
//   - the abdomen map against the uterus's ellipse (its poles at s = -1 and +1, its sides at t = -1, +1);
//   - what the fundal and Pawlik's grips are for, against the label map: the pole whose label voxels
//     lie nearest the fundus (or the pelvis), or none in a transverse lie;
//   - scripted takes: a good one (every maneuver's zones pressed at 1 N, the poles found where the label
//     map has them, the right answers) scores every answer right and reaches every maneuver; a bad one
//     (the same presses on the mother's left side only, at 5 N; a wrong presentation) is scored down on
//     exactly the grips that need both sides, the presentation, the force and the coverage;
//   - the written files reopened: the JSON's figures, the PNG's size and colours.
#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app/exercise/leopold.h"

namespace fetouch::app::exercise {
namespace {

namespace fs = std::filesystem;

imaging::PhantomGeometry posed(const config::FetalPose& pose, std::uint32_t seed = 1) {
  const config::FetalAxes axes = config::fetal_axes(pose);
  return imaging::phantom_geometry(seed, {0, 0, 0}, imaging::PhantomSettings::Orientation{axes.head, axes.back});
}

// The centroid (x, y; mm) of the label voxels for which `which` holds, on a 3 mm grid.
template <class Which>
Eigen::Vector2d centroid(const imaging::PhantomGeometry& g, Which which) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double count = 0;
  for (double x = -120; x <= 120; x += 3)
    for (double y = -100; y <= 100; y += 3)
      for (double z = -80; z <= 80; z += 3)
        if (which(g.label_at({x, y, z}), Eigen::Vector3d(x, y, z))) sum += Eigen::Vector3d(x, y, z), ++count;
  return count > 0 ? Eigen::Vector2d(sum.head<2>() / count) : Eigen::Vector2d(NAN, NAN);
}

bool is_head(std::uint8_t l) { return l == imaging::kHead || l == imaging::kSkull; }

// The breech as the label map has it: the trunk voxels on the far side of the trunk's centroid from
// the head (the limbs' hips included).
Eigen::Vector2d breech_centroid(const imaging::PhantomGeometry& g) {
  const Eigen::Vector2d head = centroid(g, [](std::uint8_t l, const Eigen::Vector3d&) { return is_head(l); });
  const Eigen::Vector2d trunk = centroid(g, [](std::uint8_t l, const Eigen::Vector3d&) { return l == imaging::kTrunk; });
  const Eigen::Vector2d away = (trunk - head).normalized();
  return centroid(g, [&](std::uint8_t l, const Eigen::Vector3d& x) {
    return l == imaging::kTrunk && (x.head<2>() - trunk).dot(away) > 0;
  });
}

TEST(Leopold, TheAbdomenMapIsTheUterusSeenFromTheFront) {
  const imaging::PhantomGeometry g = imaging::phantom_geometry(3);
  const AbdomenMap map(g);
  const auto& u = g.uterus_outer;
  const Eigen::Vector2d c(u.centre[0], u.centre[1]), along(std::cos(u.yaw), std::sin(u.yaw)), across(-std::sin(u.yaw), std::cos(u.yaw));
  const auto at = [&](const Eigen::Vector2d& p) { return map.map_mm({p.x(), p.y(), 10}); };
  EXPECT_NEAR((at(c + u.radii[0] * along) - Eigen::Vector2d(1, 0)).norm(), 0, 1e-12);    // the fundus
  EXPECT_NEAR((at(c - u.radii[0] * along) - Eigen::Vector2d(-1, 0)).norm(), 0, 1e-12);   // the lower pole
  EXPECT_NEAR((at(c + u.radii[1] * across) - Eigen::Vector2d(0, 1)).norm(), 0, 1e-12);   // the mother's right
  EXPECT_NEAR((at(c - u.radii[1] * across) - Eigen::Vector2d(0, -1)).norm(), 0, 1e-12);  // her left
  // The outline's label: wall just inside the unit circle, tissue just outside (in the plane z = 0).
  for (double a = 0; a < 2 * M_PI; a += 0.5) {
    const Eigen::Vector2d in = map.unmap_mm({0.97 * std::cos(a), 0.97 * std::sin(a)}), out = map.unmap_mm({1.03 * std::cos(a), 1.03 * std::sin(a)});
    EXPECT_EQ(g.label_at({in.x(), in.y(), u.centre[2]}), imaging::kUterineWall) << a;
    EXPECT_EQ(g.label_at({out.x(), out.y(), u.centre[2]}), imaging::kTissue) << a;
    EXPECT_NEAR((at(map.unmap_mm({0.5 * std::cos(a), 0.3 * std::sin(a)})) - Eigen::Vector2d(0.5 * std::cos(a), 0.3 * std::sin(a))).norm(), 0, 1e-12);
  }
}

TEST(Leopold, TheFundalAndPawliksGripsAreForThePolesTheLabelMapPutsThere) {
  for (const config::FetalPose& pose : config::every_pose()) {
    SCOPED_TRACE(config::describe(pose));
    const imaging::PhantomGeometry g = posed(pose);
    const AbdomenMap map(g);
    const Eigen::Vector2d head = centroid(g, [](std::uint8_t l, const Eigen::Vector3d&) { return is_head(l); });
    const Eigen::Vector2d breech = breech_centroid(g);
    const auto s = [&](const Eigen::Vector2d& p) { return map.map_mm({p.x(), p.y(), 0}).x(); };
    const std::vector<Target> fundal = maneuver_targets(Maneuver::fundal, g), pawlik = maneuver_targets(Maneuver::pawlik, g);
    ASSERT_EQ(fundal.size(), 1u);
    ASSERT_EQ(pawlik.size(), 1u);
    if (pose.lie == config::FetalLie::longitudinal) {
      const bool cephalic = pose.presentation == config::FetalPresentation::cephalic;
      EXPECT_EQ(fundal[0].what, cephalic ? "the breech" : "the head");
      EXPECT_EQ(pawlik[0].what, cephalic ? "the head" : "the breech");
      // Each target's disc holds its pole's label centroid, seen from the front.
      const Eigen::Vector2d up = cephalic ? breech : head, down = cephalic ? head : breech;
      EXPECT_LT((fundal[0].centre_mm - up).norm(), fundal[0].radius_mm) << (fundal[0].centre_mm - up).norm();
      EXPECT_LT((pawlik[0].centre_mm - down).norm(), pawlik[0].radius_mm) << (pawlik[0].centre_mm - down).norm();
      EXPECT_GT(s(up), 0.2);
      EXPECT_LT(s(down), -0.2);
    } else if (pose.lie == config::FetalLie::transverse) {
      EXPECT_EQ(fundal[0].what, "the empty fundus");
      EXPECT_EQ(pawlik[0].what, "the empty pelvis");
      EXPECT_LT(std::abs(s(head)), 0.2);  // the head lies at the side
    } else {  // oblique: the pole lower in the uterus is never the one the fundal grip is for
      const bool head_lower = s(head) < s(breech);
      if (pawlik[0].what != "the empty pelvis") {
        EXPECT_EQ(pawlik[0].what, head_lower ? "the head" : "the breech");
      }
      if (fundal[0].what != "the empty fundus") {
        EXPECT_EQ(fundal[0].what, head_lower ? "the breech" : "the head");
      }
    }
  }
}

// A scripted trainee: every maneuver's zones pressed on a 6 mm raster, the middle band too in the
// second (the back may face forwards), and the poles pressed where the label map has them; one hand
// per zone. `left_only` keeps the presses on the mother's left (t <= 0).
struct Take {
  std::vector<HandTrack> hands = std::vector<HandTrack>(2);
  std::array<double, kManeuvers - 1> next{};
  double t = 0;
  void press(int hand, const Eigen::Vector2d& xy_mm, double force) {
    HandTrack& h = hands[hand];
    h.time_s.push_back(t);
    h.position_m.emplace_back(1e-3 * xy_mm.x(), 1e-3 * xy_mm.y(), 0.05);
    h.force_n.push_back(force);
    h.in_contact.push_back(true);
    t += 0.001;
  }
};

Take scripted_take(const imaging::PhantomGeometry& g, double force, bool left_only) {
  const AbdomenMap map(g);
  const Eigen::Vector2d head = centroid(g, [](std::uint8_t l, const Eigen::Vector3d&) { return is_head(l); });
  const Eigen::Vector2d breech = breech_centroid(g);
  Take take;
  const double step_s = 6 / map.radii_mm().x(), step_t = 6 / map.radii_mm().y();
  for (int k = 0; k < kManeuvers; ++k) {
    if (k > 0) take.next[k - 1] = take.t;
    std::vector<Zone> zones = leopold_guides()[k].zones;
    if (k == 1) zones.push_back({-0.5, 0.5, -0.3, 0.3});
    for (const Zone& z : zones)
      for (double s = z.s_min; s <= z.s_max + 1e-9; s += step_s)
        for (double t = z.t_min; t <= z.t_max + 1e-9; t += step_t) {
          if (std::hypot(s, t) > 0.98 || (left_only && t > 0)) continue;
          take.press(t <= 0 ? 0 : 1, map.unmap_mm({s, t}), force);
        }
    if (k != 1)
      for (const Eigen::Vector2d& pole : {head, breech}) {
        const double t = map.map_mm({pole.x(), pole.y(), 0}).y();
        if (!(left_only && t > 0)) take.press(t <= 0 ? 0 : 1, pole, force);
      }
  }
  return take;
}

AssessmentSettings settings() {
  AssessmentSettings s;
  s.comfort_limit_n = 3;
  s.comfort_limit_source = "a test's own figure";
  return s;
}

TEST(Leopold, AGoodTakeReachesEveryManeuverAndABadOneIsScoredDownWhereItFailed) {
  config::FetalPose transverse;
  transverse.lie = config::FetalLie::transverse, transverse.presentation = config::FetalPresentation::shoulder;
  transverse.back = config::FetalBack::superior;
  const std::vector<config::FetalPose> poses{config::FetalPose{}, config::draw_pose(2), config::draw_pose(5), transverse};
  for (const config::FetalPose& pose : poses) {
    SCOPED_TRACE(config::describe(pose));
    const imaging::PhantomGeometry g = posed(pose);
    const Answers right{pose.lie, pose.presentation, pose.back};
    const Take good = scripted_take(g, 1.0, false);
    const Assessment a = assess(g, pose, good.hands, good.next, right, settings());
    for (const AnswerResult& r : a.answers) EXPECT_EQ(r.score, 1) << r.asked;
    for (const ManeuverResult& m : a.maneuvers) EXPECT_TRUE(m.reached()) << leopold_guides()[static_cast<int>(m.maneuver)].name;
    EXPECT_DOUBLE_EQ(a.largest_force_n, 1.0);
    EXPECT_EQ(a.time_over_limit_s, 0);
    EXPECT_GT(a.covered_share, 0.5);

    Answers wrong = right;
    wrong.presentation = pose.presentation == config::FetalPresentation::cephalic ? config::FetalPresentation::breech
                                                                                   : config::FetalPresentation::cephalic;
    const Take bad = scripted_take(g, 5.0, true);
    const Assessment b = assess(g, pose, bad.hands, bad.next, wrong, settings());
    EXPECT_EQ(b.answers[0].score, 1);
    EXPECT_EQ(b.answers[1].score, 0);
    EXPECT_EQ(b.answers[2].score, 1);
    // The grips that need a hand on each side: the right hand's zone never pressed.
    for (const Maneuver m : {Maneuver::umbilical, Maneuver::pelvic}) {
      const ManeuverResult& r = b.maneuvers[static_cast<int>(m)];
      EXPECT_FALSE(r.reached());
      EXPECT_TRUE(r.zones_touched[0]);
      EXPECT_FALSE(r.zones_touched[1]);
    }
    // Every press above the limit: the whole take, less the last tick of each hand.
    EXPECT_DOUBLE_EQ(b.largest_force_n, 5.0);
    EXPECT_NEAR(b.time_over_limit_s, bad.t, 0.0021);
    EXPECT_LT(b.covered_share, 0.6 * a.covered_share);
    EXPECT_GT(b.covered_share, 0.3 * a.covered_share);
  }
}

TEST(Leopold, AnOctantOffPositionScoresHalfAndAnUnansweredQuestionNothing) {
  const config::FetalPose pose;  // left_anterior
  const imaging::PhantomGeometry g = posed(pose);
  const auto score = [&](std::optional<config::FetalBack> back) {
    return assess(g, pose, {}, {0, 0, 0}, Answers{pose.lie, std::nullopt, back}, settings());
  };
  EXPECT_EQ(score(config::FetalBack::left_anterior).answers[2].score, 1);
  EXPECT_EQ(score(config::FetalBack::left).answers[2].score, 0.5);
  EXPECT_EQ(score(config::FetalBack::anterior).answers[2].score, 0.5);
  EXPECT_EQ(score(config::FetalBack::right).answers[2].score, 0);
  EXPECT_EQ(score(config::FetalBack::right_posterior).answers[2].score, 0);
  EXPECT_EQ(score(std::nullopt).answers[2].score, 0);
  EXPECT_EQ(score(std::nullopt).answers[1].score, 0);
  EXPECT_EQ(score(std::nullopt).answers[1].given, "");
  EXPECT_THROW(assess(g, pose, {}, {2, 1, 3}, Answers{}, settings()), std::invalid_argument);
}

TEST(Leopold, TheAssessmentIsWrittenAsJsonAPictureAndAReport) {
  const config::FetalPose pose = config::draw_pose(4);
  const imaging::PhantomGeometry g = posed(pose);
  const Take take = scripted_take(g, 1.0, true);
  const Assessment a = assess(g, pose, take.hands, take.next, Answers{pose.lie, pose.presentation, std::nullopt}, settings());
  const fs::path dir = fs::temp_directory_path() / ("fetouch_leopold_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  write_assessment(a, g, dir);
  const YAML::Node j = YAML::LoadFile((dir / "assessment.json").string());
  EXPECT_EQ(j["pose"]["lie"].as<std::string>(), config::to_string(pose.lie));
  EXPECT_EQ(j["answers"].size(), 3u);
  EXPECT_EQ(j["answers"][2]["given"].as<std::string>(), "");
  EXPECT_EQ(j["maneuvers"].size(), 4u);
  EXPECT_FALSE(j["maneuvers"][1]["reached"].as<bool>());
  EXPECT_DOUBLE_EQ(j["covered_share"].as<double>(), a.covered_share);
  EXPECT_EQ(j["coverage_n"].size(), 32u * 32u);
  EXPECT_EQ(j["comfort_limit_source"].as<std::string>(), "a test's own figure");
  std::stringstream report;
  report << std::ifstream(dir / "report.md").rdbuf();
  EXPECT_NE(report.str().find("(coverage.png)"), std::string::npos);
  EXPECT_NE(report.str().find("not reached"), std::string::npos);
  // The picture: the mother's left (t < 0) on the right half; pressed (green) there, untouched
  // (grey) on the left half, white outside the abdomen.
  vtkNew<vtkPNGReader> reader;
  reader->SetFileName((dir / "coverage.png").string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  // 320 pixels along the mother's axis, the width to scale.
  ASSERT_EQ(dims[1], 320);
  ASSERT_NEAR(dims[0], 320 * g.uterus_outer.radii[1] / g.uterus_outer.radii[0], 0.51);
  const int x_right = dims[0] / 2 - dims[0] / 5, x_left = dims[0] / 2 + dims[0] / 5;  // t = 0.4, t = -0.4
  const auto pixel = [&](int x, int y, int c) { return static_cast<int>(image->GetScalarComponentAsDouble(x, y, 0, c)); };
  // Of a 9 x 9 block about (x, y), the pixels that are grey (untouched) and green (pressed).
  const auto count = [&](int x0, int y0, bool green) {
    int n = 0;
    for (int x = x0 - 4; x <= x0 + 4; ++x)
      for (int y = y0 - 4; y <= y0 + 4; ++y) {
        const int r = pixel(x, y, 0), gr = pixel(x, y, 1), b = pixel(x, y, 2);
        n += green ? (gr > r + 20 && gr > b + 20) : (r == 225 && gr == 225 && b == 225);
      }
    return n;
  };
  EXPECT_EQ(pixel(2, 2, 0), 255);             // a corner: outside the abdomen
  EXPECT_GE(count(x_right, 160, false), 60);  // the mother's right, mid-height: untouched
  EXPECT_GE(count(x_left, 160, true), 60);    // her left: pressed
  if (!std::getenv("FETOUCH_KEEP_LEOPOLD")) fs::remove_all(dir);
  else std::printf("kept %s\n", dir.c_str());
}

}  // namespace
}  // namespace fetouch::app::exercise
