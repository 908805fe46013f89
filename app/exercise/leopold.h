// The four Leopold maneuvers on the phantom's fetus, and how a take of them is assessed: what each
// maneuver is for in this fetus (the parts it should reach), whether the hands reached them, how much
// of the abdomen they covered, the largest force, and whether the trainee's answers (lie,
// presentation, position) are the fetus's.
//
// The abdomen is the uterus seen from the front (+z, where the hands are), mapped to (s, t): s along
// the mother's axis, -1 at the uterus's lower pole (the pelvis) and +1 at the fundus; t across it,
// -1 at the mother's left and +1 at her right (the uterus's outer ellipsoid, turned by its yaw, is the
// unit disc). Points are in the phantom's frame (imaging/phantom.h), metres: a phantom scene's mesh is
// the label map's, whose millimetres are centred on the origin as the geometry's are.
//
// The maneuvers, as obstetrics teaches them (each one's zones are where the hands go; a maneuver
// with two zones needs both, one hand each):
//   1 fundal grip     both hands on the fundus: which pole lies there (the head round, hard and
//                     ballotable; the breech broad, soft and irregular), or none (a transverse lie)
//   2 umbilical grip  one hand on each side at the navel's level: the back (smooth, firm, continuous)
//                     on one side, the small parts (knobbly, moving) on the other
//   3 Pawlik's grip   one hand just above the symphysis: what presents at the pelvis (or nothing)
//   4 pelvic grip     both hands either side of the lower pole, pressing towards the pelvic inlet:
//                     the presenting part from both sides (how far it is engaged)
// A part counts as reached when a hand pressed with at least `palpation_force_n` within the part's
// outline seen from the front, grown by the hand's contact radius; where a maneuver finds nothing
// (no pole in the fundus, an empty pelvis), what it is for is the empty region itself.
#pragma once

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "config/fetal_pose.h"
#include "imaging/phantom.h"

namespace fetouch::app::exercise {

enum class Maneuver { fundal, umbilical, pawlik, pelvic };
constexpr int kManeuvers = 4;

// A rectangle of the abdomen's (s, t).
struct Zone {
  double s_min = 0, s_max = 0, t_min = 0, t_max = 0;
  bool contains(const Eigen::Vector2d& st) const {
    return st.x() >= s_min && st.x() <= s_max && st.y() >= t_min && st.y() <= t_max;
  }
};

struct ManeuverGuide {
  Maneuver maneuver;
  std::string name;      // "first maneuver (fundal grip)"
  std::string hands;     // where to put the hands
  std::string feel_for;  // what to feel for
  std::vector<Zone> zones;
};
const std::array<ManeuverGuide, kManeuvers>& leopold_guides();

class AbdomenMap {
 public:
  explicit AbdomenMap(const imaging::PhantomGeometry& geometry);
  // (s, t) of a point of the phantom's frame, mm.
  Eigen::Vector2d map_mm(const Eigen::Vector3d& x_mm) const;
  // The point of the frontal plane (x, y; mm) at (s, t).
  Eigen::Vector2d unmap_mm(const Eigen::Vector2d& st) const;
  const Eigen::Vector2d& radii_mm() const { return radii_; }

 private:
  Eigen::Vector2d centre_, radii_;
  double cos_ = 1, sin_ = 0;
};

// What a maneuver should reach, seen from the front: a disc of the frontal plane (mm).
struct Target {
  std::string what;  // "the head", "the breech", "the back", "the small parts", "the empty fundus", ...
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
  double radius_mm = 0;
};
// The maneuver's targets in this fetus (all of them must be reached).
std::vector<Target> maneuver_targets(Maneuver maneuver, const imaging::PhantomGeometry& geometry);

// One hand's palpation: its device's recorded ticks (positions in metres, the force it was sent).
struct HandTrack {
  std::string name;
  std::vector<double> time_s;
  std::vector<Eigen::Vector3d> position_m;
  std::vector<double> force_n;  // the force's magnitude
  std::vector<bool> in_contact;
};

struct Answers {
  std::optional<config::FetalLie> lie;
  std::optional<config::FetalPresentation> presentation;
  std::optional<config::FetalBack> back;
};

struct AssessmentSettings {
  double palpation_force_n = 0.3;  // a press that feels what lies beneath
  double hand_radius_mm = 10;      // what a press covers around its point
  // The force not to exceed, and where the figure comes from (it is reported with the result).
  double comfort_limit_n = 0;
  std::string comfort_limit_source;
  int coverage_cells = 32;  // the coverage map's cells along s and t
};

struct ManeuverResult {
  Maneuver maneuver = Maneuver::fundal;
  double start_s = 0, end_s = 0;
  std::vector<bool> zones_touched;  // per zone of the guide
  std::vector<Target> targets;
  std::vector<bool> targets_reached;
  double largest_force_n = 0;  // in contact, within the maneuver's time
  bool reached() const;  // every zone touched and every target reached
};

struct AnswerResult {
  std::string asked, given, truth;  // names ("" given: unanswered)
  // 1 right; 0.5 the position one octant off (palpation's resolution); 0 wrong or unanswered.
  double score = 0;
};

struct Assessment {
  config::FetalPose pose;
  std::array<AnswerResult, 3> answers;  // lie, presentation, position (the back)
  std::array<ManeuverResult, kManeuvers> maneuvers;
  double duration_s = 0;
  double largest_force_n = 0, time_over_limit_s = 0;
  AssessmentSettings settings;
  // The coverage map: cells x cells over (s, t) in [-1, 1]^2, row-major with s the row (s = -1 first);
  // -1 outside the abdomen (the unit disc), else the largest force pressed on the cell (0: untouched).
  std::vector<double> coverage;
  double covered_share = 0;  // of the abdomen's cells, those pressed with at least palpation_force_n
  double answer_score() const;  // the answers' scores summed (of 3)
  int maneuvers_reached() const;  // of 4
};

// Assesses a take: the hands' tracks, the times at which maneuvers 2, 3 and 4 began (the first
// begins at the take's start, the last ends at its end), and the answers. Throws
// std::invalid_argument for maneuver starts out of order.
Assessment assess(const imaging::PhantomGeometry& geometry, const config::FetalPose& pose,
                  const std::vector<HandTrack>& hands, const std::array<double, kManeuvers - 1>& next_maneuver_s,
                  const Answers& answers, const AssessmentSettings& settings);

// DIR/assessment.json, DIR/coverage.png and DIR/report.md (which shows the PNG). Throws
// std::runtime_error naming the file that cannot be written.
void write_assessment(const Assessment& assessment, const imaging::PhantomGeometry& geometry, const std::filesystem::path& dir);

}  // namespace fetouch::app::exercise
