#include "app/exercise/leopold.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace fetouch::app::exercise {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// The fetus's head and back directions: the posed fetus's axes (columns 0 and 2), or the seed's
// fetus (head along +x turned by its yaw, back up).
std::pair<Vec3, Vec3> fetal_directions(const imaging::PhantomGeometry& g) {
  if (g.trunk.axes) {
    const auto& a = *g.trunk.axes;
    return {Vec3(a[0], a[3], a[6]), Vec3(a[2], a[5], a[8])};
  }
  return {Vec3(std::cos(g.trunk.yaw), std::sin(g.trunk.yaw), 0), Vec3(0, 0, 1)};
}

Target disc(const std::string& what, const Vec3& centre_mm, double radius_mm) {
  return {what, centre_mm.head<2>(), radius_mm};
}

double mean(const std::array<double, 3>& a) { return (a[0] + a[1] + a[2]) / 3; }

// The two poles as the hands find them: the head, and the breech (the trunk's far end).
std::array<Target, 2> poles(const imaging::PhantomGeometry& g) {
  const Vec3 head_dir = fetal_directions(g).first;
  const Vec3 breech = vec(g.trunk.centre) - 0.6 * g.trunk.radii[0] * head_dir;
  return {disc("the head", vec(g.head.centre), mean(g.head.radii)),
          disc("the breech", breech, 0.5 * (g.trunk.radii[1] + g.trunk.radii[2]))};
}

// An empty region, where a maneuver finds nothing: its disc at (s, t), a fifth of the uterus across.
Target empty(const std::string& what, const AbdomenMap& map, double s, double t) {
  return {what, map.unmap_mm({s, t}), 0.2 * map.radii_mm().minCoeff()};
}

// Interval union length: the time any hand spent above the limit.
double union_length(std::vector<std::pair<double, double>> spans) {
  std::sort(spans.begin(), spans.end());
  double total = 0, from = 0, to = 0;
  bool open = false;
  for (const auto& [a, b] : spans) {
    if (open && a <= to) {
      to = std::max(to, b);
      continue;
    }
    if (open) total += to - from;
    from = a, to = b, open = true;
  }
  if (open) total += to - from;
  return total;
}

}  // namespace

const std::array<ManeuverGuide, kManeuvers>& leopold_guides() {
  static const std::array<ManeuverGuide, kManeuvers> guides{{
      {Maneuver::fundal, "first maneuver (fundal grip)",
       "both hands on the top of the uterus (the fundus), fingertips towards each other",
       "which pole lies there: the head is round, hard and can be bounced between the hands; the breech is broader, "
       "softer and irregular; an empty fundus means the fetus lies across",
       {{0.45, 1.0, -0.75, 0.75}}},
      {Maneuver::umbilical, "second maneuver (umbilical grip)",
       "one hand on each side of the abdomen at the level of the navel; steady one side while the other presses",
       "the back on one side (smooth, firm and continuous) and the small parts on the other (knobbly, they move)",
       {{-0.5, 0.5, -1.0, -0.3}, {-0.5, 0.5, 0.3, 1.0}}},
      {Maneuver::pawlik, "third maneuver (Pawlik's grip)",
       "one hand just above the pubic bone, grasping the lower pole between thumb and fingers",
       "what presents at the pelvis (the head, the breech) or nothing (a shoulder presentation)",
       {{-1.0, -0.45, -0.5, 0.5}}},
      {Maneuver::pelvic, "fourth maneuver (pelvic grip)",
       "facing the mother's feet, both hands on either side of the lower pole, pressing down towards the pelvic inlet",
       "the presenting part from both sides: whether the fingers meet below it (not engaged) or part around it",
       {{-1.0, -0.35, -0.8, -0.05}, {-1.0, -0.35, 0.05, 0.8}}},
  }};
  return guides;
}

AbdomenMap::AbdomenMap(const imaging::PhantomGeometry& geometry)
    : centre_(geometry.uterus_outer.centre[0], geometry.uterus_outer.centre[1]),
      radii_(geometry.uterus_outer.radii[0], geometry.uterus_outer.radii[1]),
      cos_(std::cos(geometry.uterus_outer.yaw)),
      sin_(std::sin(geometry.uterus_outer.yaw)) {}

Eigen::Vector2d AbdomenMap::map_mm(const Eigen::Vector3d& x_mm) const {
  const Eigen::Vector2d d = x_mm.head<2>() - centre_;
  return {(cos_ * d.x() + sin_ * d.y()) / radii_.x(), (-sin_ * d.x() + cos_ * d.y()) / radii_.y()};
}

Eigen::Vector2d AbdomenMap::unmap_mm(const Eigen::Vector2d& st) const {
  const Eigen::Vector2d local(st.x() * radii_.x(), st.y() * radii_.y());
  return centre_ + Eigen::Vector2d(cos_ * local.x() - sin_ * local.y(), sin_ * local.x() + cos_ * local.y());
}

std::vector<Target> maneuver_targets(Maneuver maneuver, const imaging::PhantomGeometry& g) {
  const AbdomenMap map(g);
  std::array<Target, 2> pole = poles(g);
  const auto s_of = [&](const Target& t) { return map.map_mm({t.centre_mm.x(), t.centre_mm.y(), 0}).x(); };
  if (s_of(pole[0]) < s_of(pole[1])) std::swap(pole[0], pole[1]);  // pole[0] the fundal one
  const Target& fundal = pole[0];
  const Target& presenting = pole[1];
  // A pole counts as in the fundus or over the pelvis when it lies in that fifth of the uterus's length.
  const bool in_fundus = s_of(fundal) >= 0.2, at_pelvis = s_of(presenting) <= -0.2;
  switch (maneuver) {
    case Maneuver::fundal:
      return {in_fundus ? fundal : empty("the empty fundus", map, 0.75, 0)};
    case Maneuver::umbilical: {
      const Vec3 back = vec(g.trunk.centre) + g.trunk.radii[2] * fetal_directions(g).second;
      Vec3 ends = Vec3::Zero();
      for (const auto& limb : g.limbs) ends += vec(limb.b) / 4;
      double spread = 10;
      for (const auto& limb : g.limbs) spread = std::max(spread, (vec(limb.b) - ends).head<2>().norm() + limb.radius);
      return {disc("the back", back, 0.5 * g.trunk.radii[0]), disc("the small parts", ends, spread)};
    }
    case Maneuver::pawlik:
      return {at_pelvis ? presenting : empty("the empty pelvis", map, -0.75, 0)};
    case Maneuver::pelvic: {
      if (!at_pelvis) return {empty("the empty pelvis (mother's left)", map, -0.7, -0.35), empty("the empty pelvis (mother's right)", map, -0.7, 0.35)};
      // Either side of the presenting part, across the mother's axis.
      const Eigen::Vector2d across = (map.unmap_mm({0, 1}) - map.unmap_mm({0, 0})).normalized();
      const double r = presenting.radius_mm;
      Target left = presenting, right = presenting;
      left.what += " (mother's left)", right.what += " (mother's right)";
      left.centre_mm -= 0.6 * r * across, right.centre_mm += 0.6 * r * across;
      left.radius_mm = right.radius_mm = 0.6 * r;
      return {left, right};
    }
  }
  return {};
}

double Assessment::answer_score() const {
  double sum = 0;
  for (const AnswerResult& r : answers) sum += r.score;
  return sum;
}

int Assessment::maneuvers_reached() const {
  return static_cast<int>(std::count_if(maneuvers.begin(), maneuvers.end(), [](const ManeuverResult& m) { return m.reached(); }));
}

bool ManeuverResult::reached() const {
  return std::all_of(zones_touched.begin(), zones_touched.end(), [](bool b) { return b; }) &&
         std::all_of(targets_reached.begin(), targets_reached.end(), [](bool b) { return b; });
}

namespace {

AnswerResult judge_lie(const std::optional<config::FetalLie>& given, config::FetalLie truth) {
  AnswerResult r{"lie", given ? config::to_string(*given) : "", config::to_string(truth), 0};
  r.score = given && *given == truth ? 1 : 0;
  return r;
}

AnswerResult judge_presentation(const std::optional<config::FetalPresentation>& given, config::FetalPresentation truth) {
  AnswerResult r{"presentation", given ? config::to_string(*given) : "", config::to_string(truth), 0};
  r.score = given && *given == truth ? 1 : 0;
  return r;
}

// The back: right, or half right when it is one octant off (45 degrees), as far as palpation can
// tell the back's side apart from its turn.
AnswerResult judge_back(const std::optional<config::FetalBack>& given, const config::FetalPose& truth) {
  AnswerResult r{"position (the back)", given ? config::to_string(*given) : "", config::to_string(truth.back), 0};
  if (!given) return r;
  if (*given == truth.back) {
    r.score = 1;
    return r;
  }
  config::FetalPose answered = truth;
  answered.back = *given;
  try {
    const auto a = config::fetal_axes(answered).back, b = config::fetal_axes(truth).back;
    const double cosine = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if (cosine >= std::cos(46.0 * M_PI / 180)) r.score = 0.5;
  } catch (const std::invalid_argument&) {
    // A back this lie cannot have: wrong.
  }
  return r;
}

}  // namespace

Assessment assess(const imaging::PhantomGeometry& geometry, const config::FetalPose& pose, const std::vector<HandTrack>& hands,
                  const std::array<double, kManeuvers - 1>& next_maneuver_s, const Answers& answers,
                  const AssessmentSettings& settings) {
  for (int k = 1; k < kManeuvers - 1; ++k)
    if (!(next_maneuver_s[k] >= next_maneuver_s[k - 1]))
      throw std::invalid_argument("assess: maneuver " + std::to_string(k + 2) + " begins before maneuver " + std::to_string(k + 1));
  if (!(settings.coverage_cells > 0)) throw std::invalid_argument("assess: the coverage map needs at least one cell");
  Assessment a;
  a.pose = pose;
  a.settings = settings;
  a.answers = {judge_lie(answers.lie, pose.lie), judge_presentation(answers.presentation, pose.presentation),
               judge_back(answers.back, pose)};

  double first = INFINITY, last = -INFINITY;
  for (const HandTrack& h : hands)
    if (!h.time_s.empty()) first = std::min(first, h.time_s.front()), last = std::max(last, h.time_s.back());
  if (!(first <= last)) first = last = 0;
  a.duration_s = last - first;
  const std::array<double, kManeuvers + 1> bounds{first, next_maneuver_s[0], next_maneuver_s[1], next_maneuver_s[2], last};
  const auto maneuver_at = [&](double t) {
    int k = 0;
    while (k + 1 < kManeuvers && t >= bounds[k + 1]) ++k;
    return k;
  };

  const AbdomenMap map(geometry);
  for (int k = 0; k < kManeuvers; ++k) {
    ManeuverResult& m = a.maneuvers[k];
    m.maneuver = static_cast<Maneuver>(k);
    m.start_s = bounds[k], m.end_s = bounds[k + 1];
    m.zones_touched.assign(leopold_guides()[k].zones.size(), false);
    m.targets = maneuver_targets(m.maneuver, geometry);
    m.targets_reached.assign(m.targets.size(), false);
  }

  const int n = settings.coverage_cells;
  a.coverage.assign(std::size_t(n) * n, 0.0);
  const auto cell_centre = [n](int i) { return -1 + (i + 0.5) * 2.0 / n; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (std::hypot(cell_centre(i), cell_centre(j)) > 1) a.coverage[std::size_t(i) * n + j] = -1;
  const double ds = settings.hand_radius_mm / map.radii_mm().x(), dt = settings.hand_radius_mm / map.radii_mm().y();

  std::vector<std::pair<double, double>> over_limit;
  for (const HandTrack& h : hands) {
    const std::size_t count = std::min({h.time_s.size(), h.position_m.size(), h.force_n.size(), h.in_contact.size()});
    for (std::size_t i = 0; i < count; ++i) {
      const double f = h.force_n[i];
      a.largest_force_n = std::max(a.largest_force_n, f);
      if (settings.comfort_limit_n > 0 && f > settings.comfort_limit_n) {
        const double step = i + 1 < count ? h.time_s[i + 1] - h.time_s[i] : i > 0 ? h.time_s[i] - h.time_s[i - 1] : 0;
        over_limit.emplace_back(h.time_s[i], h.time_s[i] + step);
      }
      if (!h.in_contact[i]) continue;
      const Eigen::Vector3d x_mm = 1e3 * h.position_m[i];
      const Eigen::Vector2d st = map.map_mm(x_mm);
      // The coverage map: every cell whose centre lies within the hand's radius of the press.
      const int i0 = std::max(0, int(std::floor((st.x() - ds + 1) * n / 2))), i1 = std::min(n - 1, int(std::floor((st.x() + ds + 1) * n / 2)));
      const int j0 = std::max(0, int(std::floor((st.y() - dt + 1) * n / 2))), j1 = std::min(n - 1, int(std::floor((st.y() + dt + 1) * n / 2)));
      for (int ci = i0; ci <= i1; ++ci)
        for (int cj = j0; cj <= j1; ++cj) {
          double& cell = a.coverage[std::size_t(ci) * n + cj];
          const double u = (cell_centre(ci) - st.x()) / ds, v = (cell_centre(cj) - st.y()) / dt;
          if (cell >= 0 && u * u + v * v <= 1) cell = std::max(cell, f);
        }
      ManeuverResult& m = a.maneuvers[maneuver_at(h.time_s[i])];
      m.largest_force_n = std::max(m.largest_force_n, f);
      if (f < settings.palpation_force_n) continue;
      const auto& zones = leopold_guides()[static_cast<int>(m.maneuver)].zones;
      for (std::size_t z = 0; z < zones.size(); ++z)
        if (zones[z].contains(st)) m.zones_touched[z] = true;
      for (std::size_t t = 0; t < m.targets.size(); ++t)
        if ((x_mm.head<2>() - m.targets[t].centre_mm).norm() <= m.targets[t].radius_mm + settings.hand_radius_mm)
          m.targets_reached[t] = true;
    }
  }
  a.time_over_limit_s = union_length(std::move(over_limit));
  int inside = 0, covered = 0;
  for (const double c : a.coverage) {
    inside += c >= 0;
    covered += c >= settings.palpation_force_n;
  }
  a.covered_share = inside > 0 ? double(covered) / inside : 0;
  return a;
}

}  // namespace fetouch::app::exercise
