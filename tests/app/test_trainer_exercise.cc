// `fetouch trainer --exercise leopold`, the real binary in a real window under Xvfb (label gui),
// with two scripted hands on config/scenes/leopold.yaml's phantom (seed 1: a longitudinal lie,
// cephalic presentation, the poles on the mother's midline):
//   - a good take: every maneuver's zones pressed 14 mm deep by the default hand (300 N/m), the poles
//     pressed where the label map has them, the right answers: every answer right, every maneuver
//     reached;
//   - a bad take: the same presses on the mother's left side only, 27 mm deep by a stiff hand
//     (1500 N/m; at 24 mm the head's press plateaued within 3 % of the limit on one fresh mesh, see
//     docs/trainer.md), the wrong presentation: the two-handed grips (umbilical, pelvic) lose their
//     right hand's zone, the fundal and Pawlik's grips still reach the midline poles, the presentation is wrong, the force passes a
//     limit set at 1.3 times the good take's largest force and the coverage drops;
//   - `fetouch review` of the good take: its screenshot with the paths differs from the one without
//     them where the recorded presses project through the view's camera (the projection done here),
//     is red where the largest force was pressed, and is the same far from every path.
// The expectations come from the label map and the scripts, not from the program.
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "app/exercise/leopold.h"
#include "app/recording.h"
#include "tests/support/run_command.h"
#include "tests/support/scene_variant.h"
#include "tests/support/test_paths.h"

namespace fetouch::testing {
namespace {

namespace fs = std::filesystem;
using app::exercise::AbdomenMap;

const fs::path kScene = fs::path(FETOUCH_SOURCE_DIR) / "config" / "scenes" / "leopold.yaml";
constexpr std::uint32_t kSeed = 1;

// The scene's phantom as the exercise makes it: seed 1, the fetus 15 mm forward, the pose drawn from the seed.
imaging::PhantomGeometry exercise_phantom() {
  const config::FetalAxes axes = config::fetal_axes(config::draw_pose(kSeed));
  return imaging::phantom_geometry(kSeed, {0, 0, 15}, imaging::PhantomSettings::Orientation{axes.head, axes.back});
}

// The label voxels' centroid (x, y; mm) of the head, and of the trunk's half away from it.
std::pair<Eigen::Vector2d, Eigen::Vector2d> poles(const imaging::PhantomGeometry& g) {
  const auto centroid = [&](auto which) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double n = 0;
    for (double x = -100; x <= 100; x += 2)
      for (double y = -80; y <= 80; y += 2)
        for (double z = -60; z <= 60; z += 2)
          if (which(g.label_at({x, y, z}), Eigen::Vector2d(x, y))) sum += Eigen::Vector2d(x, y), ++n;
    return Eigen::Vector2d(sum / n);
  };
  const Eigen::Vector2d head = centroid([](std::uint8_t l, const Eigen::Vector2d&) { return l == imaging::kHead || l == imaging::kSkull; });
  const Eigen::Vector2d trunk = centroid([](std::uint8_t l, const Eigen::Vector2d&) { return l == imaging::kTrunk; });
  const Eigen::Vector2d away = (trunk - head).normalized();
  const Eigen::Vector2d breech = centroid([&](std::uint8_t l, const Eigen::Vector2d& p) { return l == imaging::kTrunk && (p - trunk).dot(away) > 0; });
  return {head, breech};
}

// Two hands' scripted paths (the virtual operator's hand follows them through its spring). A press:
// the hand rises to 8 mm above the uterus's top (0.2 s), crosses to over the point (0.6 s), comes to
// 8 mm out from the surface there (0.3 s), presses to `depth_mm` in along the normal (0.4 s), holds
// (0.4 s) and comes back out (0.4 s): slowly, as palpation goes. The hand is the one on the
// point's side (t <= 0: the left); the other waits where it last was.
struct Script {
  const AbdomenMap& map;
  const imaging::PhantomGeometry::Ellipsoid& uterus;  // its outer surface
  std::vector<std::vector<std::array<double, 4>>> rows{2};  // t, x, y, z (m)
  std::array<double, 3> maneuver_times{};
  double t = 0;

  // The point `height_mm` out along the uterus's outer normal from its surface at (s, t) (pressing:
  // a negative height).
  Eigen::Vector3d above(const Eigen::Vector2d& st, double height_mm) const {
    const Eigen::Vector2d xy = map.unmap_mm(st);
    const double w = std::sqrt(std::max(0.0, 1 - st.squaredNorm()));
    const auto& r = uterus.radii;
    const Eigen::Vector2d across_local(st.x() / r[0], st.y() / r[1]);
    const double c = std::cos(uterus.yaw), s = std::sin(uterus.yaw);
    Eigen::Vector3d normal(c * across_local.x() - s * across_local.y(), s * across_local.x() + c * across_local.y(), w / r[2]);
    normal.normalize();
    return 1e-3 * (Eigen::Vector3d(xy.x(), xy.y(), uterus.centre[2] + r[2] * w) + height_mm * normal);
  }
  void add(int hand, const Eigen::Vector3d& x) { rows[hand].push_back({t, x.x(), x.y(), x.z()}); }
  Eigen::Vector3d last(int hand) const {
    const auto& r = rows[hand].back();
    return {r[1], r[2], r[3]};
  }
  void start() {
    t = 0;
    add(0, above({0, -0.6}, 8)), add(1, above({0, 0.6}, 8));
  }
  void press(const Eigen::Vector2d& st, double depth_mm) {
    const int hand = st.y() <= 0 ? 0 : 1;
    const double travel = 1e-3 * (uterus.centre[2] + uterus.radii[2] + 8);
    Eigen::Vector3d from = last(hand);
    if (rows[hand].back()[0] < t) add(hand, from);  // still until now
    t += 0.2, from.z() = travel, add(hand, from);
    Eigen::Vector3d over = above(st, 8);
    over.z() = travel;
    t += 0.6, add(hand, over);
    t += 0.3, add(hand, above(st, 8));
    t += 0.4, add(hand, above(st, -depth_mm));
    t += 0.4, add(hand, above(st, -depth_mm));
    t += 0.4, add(hand, above(st, 8));
  }
  void write(const fs::path& dir) const {
    for (int h = 0; h < 2; ++h) {
      std::ofstream out(dir / (h == 0 ? "left.csv" : "right.csv"));
      out << "t_s,x_m,y_m,z_m\n";
      out.precision(17);
      for (const auto& r : rows[h]) out << r[0] << "," << r[1] << "," << r[2] << "," << r[3] << "\n";
      const auto& last = rows[h].back();
      out << t + 0.5 << "," << last[1] << "," << last[2] << "," << last[3] << "\n";  // both end together
    }
  }
};

Script leopold_script(const imaging::PhantomGeometry& g, const AbdomenMap& map, double depth_mm, bool left_only) {
  const auto [head, breech] = poles(g);
  const auto st = [&](const Eigen::Vector2d& xy) { return map.map_mm({xy.x(), xy.y(), 0}); };
  const bool head_down = st(head).x() < st(breech).x();
  const Eigen::Vector2d fundal = st(head_down ? breech : head), presenting = st(head_down ? head : breech);
  Script s{map, g.uterus_outer};
  s.start();
  const auto press = [&](const Eigen::Vector2d& p) {
    if (!(left_only && p.y() > 0)) s.press(p, depth_mm);
  };
  // 1: the fundus, and its pole.
  press({0.7, 0.0});
  press(fundal);
  // 2: the navel's level, a hand each side.
  s.maneuver_times[0] = s.t;
  for (const double sv : {-0.2, 0.2})
    for (const double t : {-0.45, 0.45}) press({sv, t});
  // 3: above the symphysis, and the presenting part.
  s.maneuver_times[1] = s.t;
  press({-0.6, 0.0});
  press(presenting);
  // 4: either side of the lower pole, and either side of the presenting part.
  s.maneuver_times[2] = s.t;
  for (const double t : {-0.3, 0.3}) press({-0.6, t});
  for (const double t : {-0.15, 0.15}) press({presenting.x(), presenting.y() + t});
  return s;
}

struct TakeResult {
  int exit_code = -1;
  std::string err;
  YAML::Node assessment;
};

// One take: the script, the scene with the two hands on it (virtual operators of the given
// stiffness), the real `fetouch trainer` in lockstep, the assessment it wrote.
TakeResult run_take(const fs::path& dir, double depth_mm, double hand_n_per_m, bool left_only, const std::string& answers,
                    double limit_n, const std::string& pictures = "") {
  const imaging::PhantomGeometry g = exercise_phantom();
  const AbdomenMap map(g);
  const Script s = leopold_script(g, map, depth_mm, left_only);
  fs::create_directories(dir);
  s.write(dir);
  std::string text = read_file_text(kScene);
  for (const char* hand : {"left", "right"}) {
    const std::string from = "type: phantom\n      name: " + std::string(hand);
    const std::size_t at = text.find(from);
    if (at == std::string::npos) return {};
    text.replace(at, from.size(), "type: operator\n      trajectory: " + (dir / (std::string(hand) + ".csv")).string() +
                                      "\n      hand: {stiffness_n_per_m: " + std::to_string(hand_n_per_m) + "}");
  }
  std::ofstream(dir / "scene.yaml") << text;
  char times[100];
  std::snprintf(times, sizeof times, "%.3f,%.3f,%.3f", s.maneuver_times[0], s.maneuver_times[1], s.maneuver_times[2]);
  std::string command = "trainer " + (dir / "scene.yaml").string() + " --exercise leopold --seed " + std::to_string(kSeed) +
                        " --maneuvers " + times + " --answers " + answers + " --duration " + std::to_string(s.t + 0.3) +
                        " --clock lockstep --out " + (dir / "out").string() + " --json";
  if (limit_n > 0) command += " --comfort-limit " + std::to_string(limit_n);
  if (!pictures.empty()) command += " --step-screenshots " + pictures + " --screenshot " + pictures + "/revealed.png";
  const auto r = run_command(fetouch(command));
  TakeResult result{r.exit_code, r.err, {}};
  if (r.exit_code == 0) result.assessment = YAML::LoadFile((dir / "out" / "exercise" / "assessment.json").string());
  return result;
}

// A screenshot read back: its pixels by (column, row from the top).
struct Picture {
  vtkNew<vtkPNGReader> reader;
  int width = 0, height = 0;
  explicit Picture(const fs::path& png) {
    reader->SetFileName(png.string().c_str());
    reader->Update();
    int dims[3];
    reader->GetOutput()->GetDimensions(dims);
    width = dims[0], height = dims[1];
  }
  std::array<int, 3> at(int x, int y) const {
    std::array<int, 3> c{};
    if (x < 0 || y < 0 || x >= width || y >= height) return c;
    for (int k = 0; k < 3; ++k) c[k] = static_cast<int>(reader->GetOutput()->GetScalarComponentAsDouble(x, height - 1 - y, 0, k));
    return c;
  }
};

// The pixel of the screenshot where a point (m) is drawn: a pinhole camera as the JSON describes it
// (vertical view angle), in the view's rectangle.
Eigen::Vector2d project(const YAML::Node& shown, const Eigen::Vector3d& p) {
  const auto vec = [](const YAML::Node& n) { return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>()); };
  const YAML::Node& c = shown["camera"];
  const Eigen::Vector3d eye = vec(c["position"]), d = (vec(c["focal_point"]) - eye).normalized();
  const Eigen::Vector3d right = d.cross(vec(c["view_up"])).normalized(), up = right.cross(d);
  const double w = shown["view"]["width"].as<double>(), h = shown["view"]["height"].as<double>();
  const double tan_half = std::tan(0.5 * c["view_angle_deg"].as<double>() * M_PI / 180);
  const Eigen::Vector3d v = p - eye;
  const double depth = v.dot(d);
  const double x = v.dot(right) / (depth * tan_half) * (h / w), y = v.dot(up) / (depth * tan_half);
  return {shown["view"]["x"].as<double>() + 0.5 * (x + 1) * w, shown["view"]["y"].as<double>() + 0.5 * (1 - y) * h};
}

// `fetouch review` of an exercise's folder draws the recorded paths over the anatomy.
void check_review(const fs::path& exercise_dir) {
  const fs::path with = exercise_dir / "review.png", without = exercise_dir / "review-no-paths.png";
  const auto shot = [&](const fs::path& png, bool paths) {
    const auto r = run_command(fetouch("review " + exercise_dir.string() + " --screenshot " + png.string() + " --json" +
                                       (paths ? "" : " --no-paths")));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? YAML::Load(r.out) : YAML::Node();
  };
  const YAML::Node shown = shot(with, true), bare = shot(without, false);
  ASSERT_TRUE(shown && bare);
  ASSERT_TRUE(shown["exercise"].as<bool>());
  EXPECT_EQ(shown["answer_score"].as<double>(), 3);
  ASSERT_FALSE(shown["camera"]["parallel"].as<bool>());
  const Picture a(with), b(without);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  const app::Recording take = app::read_recording(exercise_dir / "take.h5");
  ASSERT_EQ(take.devices.size(), 2u);
  // Every 50th tick of each press projected: the picture with paths differs there (within 2 px).
  std::vector<Eigen::Vector2d> drawn;
  int presses = 0, marked = 0;
  double largest = 0;
  Eigen::Vector2d hardest = Eigen::Vector2d::Zero();
  for (const app::RecordedDevice& d : take.devices)
    for (std::size_t i = 0; i < d.samples.size(); i += 10) {
      const Eigen::Vector2d px = project(shown, d.samples[i].position);
      drawn.push_back(px);
      if (!d.samples[i].in_contact) continue;
      if (d.samples[i].force.norm() > largest) largest = d.samples[i].force.norm(), hardest = px;
      if (i % 50 != 0) continue;
      ++presses;
      bool differs = false;
      for (int dx = -2; dx <= 2; ++dx)
        for (int dy = -2; dy <= 2; ++dy) {
          const auto p = a.at(int(px.x()) + dx, int(px.y()) + dy), q = b.at(int(px.x()) + dx, int(px.y()) + dy);
          differs = differs || std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2]) > 90;
        }
      marked += differs;
    }
  ASSERT_GT(presses, 50);
  EXPECT_GE(marked, presses * 95 / 100) << marked << " of " << presses << " pressed points drawn";
  // Where the largest force was pressed: red (the top of the force scale).
  bool red = false;
  for (int dx = -2; dx <= 2; ++dx)
    for (int dy = -2; dy <= 2; ++dy) {
      const auto p = a.at(int(hardest.x()) + dx, int(hardest.y()) + dy);
      red = red || (p[0] > 200 && p[1] < 110 && p[2] < 90);
    }
  EXPECT_TRUE(red) << "no red at " << hardest.transpose();
  // Far (over 20 px) from every path point, the two pictures are the same: the middle 70 % of the
  // view across (the force's colour bar is on its left).
  const double x0 = shown["view"]["x"].as<double>(), y0 = shown["view"]["y"].as<double>();
  const double w = shown["view"]["width"].as<double>(), h = shown["view"]["height"].as<double>();
  long far = 0, same = 0;
  for (int y = int(y0 + 10); y < int(y0 + h - 10); y += 7)
    for (int x = int(x0 + 0.15 * w); x < int(x0 + 0.85 * w); x += 7) {
      const Eigen::Vector2d here(x, y);
      if (std::any_of(drawn.begin(), drawn.end(), [&](const Eigen::Vector2d& p) { return (p - here).norm() < 20; })) continue;
      ++far;
      same += a.at(x, y) == b.at(x, y);
    }
  ASSERT_GT(far, 1000);
  EXPECT_GE(same, far * 99 / 100) << same << " of " << far << " pixels far from the paths unchanged";
  std::printf("review: %d of %d pressed points drawn; %ld of %ld pixels far from the paths unchanged\n", marked, presses, same, far);
}

TEST(TrainerExercise, AGoodTakeScoresRightAndABadOneIsScoredDownWhereItFailed) {
  if (!std::getenv("DISPLAY")) GTEST_SKIP() << "needs a display (xvfb-run -a)";
  const config::FetalPose pose = config::draw_pose(kSeed);
  ASSERT_EQ(pose.lie, config::FetalLie::longitudinal);  // the premise of the left-only expectations below
  const fs::path dir = fs::temp_directory_path() / ("fetouch_exercise_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string right = std::string(config::to_string(pose.lie)) + "," + config::to_string(pose.presentation) + "," +
                            config::to_string(pose.back);
  // FETOUCH_EXERCISE_PICTURES=DIR: the good take's steps pictured there (docs/trainer.md's walkthrough).
  const char* pictures = std::getenv("FETOUCH_EXERCISE_PICTURES");
  const TakeResult good = run_take(dir / "good", 12, 300, false, right, 0, pictures ? pictures : "");
  ASSERT_EQ(good.exit_code, 0) << good.err;
  const YAML::Node& a = good.assessment;
  for (const auto& answer : a["answers"]) EXPECT_EQ(answer["score"].as<double>(), 1) << answer["asked"].as<std::string>();
  for (const auto& m : a["maneuvers"]) {
    EXPECT_TRUE(m["reached"].as<bool>()) << m["name"].as<std::string>();
    EXPECT_GT(m["largest_force_n"].as<double>(), 0.3) << m["name"].as<std::string>();
  }
  const double good_force = a["largest_force_n"].as<double>(), good_cover = a["covered_share"].as<double>();
  std::printf("good take: largest force %.2f N, covered %.0f %%\n", good_force, 100 * good_cover);
  check_review(dir / "good" / "out" / "exercise");
  if (pictures) fs::copy_file(dir / "good" / "out" / "exercise" / "review.png", fs::path(pictures) / "review.png", fs::copy_options::overwrite_existing);

  const std::string wrong = std::string(config::to_string(pose.lie)) + "," +
                            (pose.presentation == config::FetalPresentation::cephalic ? "breech" : "cephalic") + "," +
                            config::to_string(pose.back);
  const TakeResult bad = run_take(dir / "bad", 33, 1500, true, wrong, 1.3 * good_force);
  ASSERT_EQ(bad.exit_code, 0) << bad.err;
  const YAML::Node& b = bad.assessment;
  EXPECT_EQ(b["answers"][0]["score"].as<double>(), 1);
  EXPECT_EQ(b["answers"][1]["score"].as<double>(), 0);
  EXPECT_EQ(b["answers"][2]["score"].as<double>(), 1);
  EXPECT_TRUE(b["maneuvers"][0]["reached"].as<bool>());   // the fundal pole lies on the midline
  EXPECT_FALSE(b["maneuvers"][1]["reached"].as<bool>());  // no right hand at the navel
  EXPECT_FALSE(b["maneuvers"][1]["zones_touched"][1].as<bool>());
  EXPECT_TRUE(b["maneuvers"][2]["reached"].as<bool>());   // the presenting part on the midline
  EXPECT_FALSE(b["maneuvers"][3]["reached"].as<bool>());  // no right hand at the pelvis
  EXPECT_FALSE(b["maneuvers"][3]["zones_touched"][1].as<bool>());
  EXPECT_GT(b["largest_force_n"].as<double>(), 1.3 * good_force);
  EXPECT_GT(b["time_over_limit_s"].as<double>(), 0.05);
  EXPECT_LT(b["covered_share"].as<double>(), 0.8 * good_cover);
  std::printf("bad take: largest force %.2f N, %.2f s above %.2f N, covered %.0f %%\n", b["largest_force_n"].as<double>(),
              b["time_over_limit_s"].as<double>(), 1.3 * good_force, 100 * b["covered_share"].as<double>());
  if (!HasFailure() && !std::getenv("FETOUCH_KEEP_EXERCISE")) fs::remove_all(dir);  // else kept for a look: the takes, their scenes and scripts
}

}  // namespace
}  // namespace fetouch::testing
