#include "config/fetal_pose.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace fetouch::config {

namespace {

using Vec = std::array<double, 3>;

template <class E>
const char* name_in(const std::vector<std::string>& names, E value) {
  const auto i = static_cast<std::size_t>(value);
  return i < names.size() ? names[i].c_str() : "?";
}

template <class E>
bool parse_in(const std::vector<std::string>& names, const std::string& name, E& out) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return out = static_cast<E>(i), true;
  return false;
}

Vec unit(Vec v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Vec head_direction(const FetalPose& pose) {
  const double towards_fundus = pose.presentation == FetalPresentation::breech ? 1.0 : -1.0;
  const double towards_right = pose.head_side == MaternalSide::right ? 1.0 : -1.0;
  switch (pose.lie) {
    case FetalLie::longitudinal: return {towards_fundus, 0, 0};
    case FetalLie::transverse: return {0, towards_right, 0};
    case FetalLie::oblique: return unit({towards_fundus, towards_right, 0});
  }
  return {0, 0, 0};
}

Vec back_request(FetalBack back) {
  constexpr double h = 0.70710678118654752;
  switch (back) {
    case FetalBack::left: return {0, -1, 0};
    case FetalBack::right: return {0, 1, 0};
    case FetalBack::anterior: return {0, 0, 1};
    case FetalBack::posterior: return {0, 0, -1};
    case FetalBack::left_anterior: return {0, -h, h};
    case FetalBack::right_anterior: return {0, h, h};
    case FetalBack::left_posterior: return {0, -h, -h};
    case FetalBack::right_posterior: return {0, h, -h};
    case FetalBack::superior: return {1, 0, 0};
    case FetalBack::inferior: return {-1, 0, 0};
  }
  return {0, 0, 0};
}

// A back within 60 degrees of the head's axis is refused (its cosine over a half).
constexpr double kLargestAxisCosine = 0.5 + 1e-9;

// The presentation and back a lie has when only the lie is named.
FetalPose default_pose(FetalLie lie) {
  FetalPose pose;
  pose.lie = lie;
  if (lie == FetalLie::transverse) pose.presentation = FetalPresentation::shoulder, pose.back = FetalBack::anterior;
  return pose;
}

// Empty when a fetus can take the pose here, else why not.
std::string why_invalid(const FetalPose& pose) {
  const bool transverse = pose.lie == FetalLie::transverse, shoulder = pose.presentation == FetalPresentation::shoulder;
  if (transverse && !shoulder)
    return std::string("a transverse lie presents the shoulder, not ") + to_string(pose.presentation);
  if (shoulder && !transverse)
    return std::string("a shoulder presentation needs a transverse lie, not ") + to_string(pose.lie);
  if (std::abs(dot(head_direction(pose), back_request(pose.back))) > kLargestAxisCosine)
    return std::string("the back cannot face ") + to_string(pose.back) + " in a" +
           (pose.lie == FetalLie::longitudinal ? " longitudinal" : pose.lie == FetalLie::transverse ? " transverse" : "n oblique") +
           " lie: that is along the fetus's own axis";
  return {};
}

}  // namespace

const std::vector<std::string>& lie_names() {
  static const std::vector<std::string> names{"longitudinal", "transverse", "oblique"};
  return names;
}
const std::vector<std::string>& presentation_names() {
  static const std::vector<std::string> names{"cephalic", "breech", "shoulder"};
  return names;
}
const std::vector<std::string>& back_names() {
  static const std::vector<std::string> names{"left",           "right",          "anterior",
                                              "posterior",      "left_anterior",  "right_anterior",
                                              "left_posterior", "right_posterior", "superior",
                                              "inferior"};
  return names;
}
const std::vector<std::string>& side_names() {
  static const std::vector<std::string> names{"left", "right"};
  return names;
}

const std::vector<std::string>& requested_lie_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = lie_names();
    n.push_back("random");
    return n;
  }();
  return names;
}

const char* to_string(FetalLie value) { return name_in(lie_names(), value); }
const char* to_string(FetalPresentation value) { return name_in(presentation_names(), value); }
const char* to_string(FetalBack value) { return name_in(back_names(), value); }
const char* to_string(MaternalSide value) { return name_in(side_names(), value); }
bool parse(const std::string& name, FetalLie& out) { return parse_in(lie_names(), name, out); }
bool parse(const std::string& name, FetalPresentation& out) { return parse_in(presentation_names(), name, out); }
bool parse(const std::string& name, FetalBack& out) { return parse_in(back_names(), name, out); }
bool parse(const std::string& name, MaternalSide& out) { return parse_in(side_names(), name, out); }

FetalAxes fetal_axes(const FetalPose& pose) {
  if (const std::string why = why_invalid(pose); !why.empty()) throw std::invalid_argument(why);
  FetalAxes axes;
  axes.head = head_direction(pose);
  const Vec b = back_request(pose.back);
  const double along = dot(b, axes.head);
  axes.back = unit({b[0] - along * axes.head[0], b[1] - along * axes.head[1], b[2] - along * axes.head[2]});
  return axes;
}

std::vector<FetalPose> every_pose() {
  std::vector<FetalPose> poses;
  for (std::size_t l = 0; l < lie_names().size(); ++l)
    for (std::size_t p = 0; p < presentation_names().size(); ++p)
      for (std::size_t b = 0; b < back_names().size(); ++b)
        for (std::size_t s = 0; s < side_names().size(); ++s) {
          const FetalPose pose{static_cast<FetalLie>(l), static_cast<FetalPresentation>(p), static_cast<FetalBack>(b),
                               static_cast<MaternalSide>(s)};
          if (pose.lie == FetalLie::longitudinal && pose.head_side != MaternalSide::left) continue;  // no side
          if (why_invalid(pose).empty()) poses.push_back(pose);
        }
  return poses;
}

FetalPose draw_pose(std::uint32_t seed) {
  std::mt19937 engine(seed ^ 0x5bd1e995u);  // apart from the phantom's own draws from the seed
  const std::vector<FetalPose> poses = every_pose();
  return poses[engine() % poses.size()];
}

std::optional<FetalPose> requested_pose(const std::string& lie, const std::string& presentation, const std::string& back,
                                        const std::string& head_side, std::uint32_t seed) {
  // The first of the other names given: where a name that cannot stand beside the lie is.
  const char* other = !presentation.empty() ? "presentation" : !back.empty() ? "back" : !head_side.empty() ? "head_side" : nullptr;
  if (lie.empty()) {
    if (other) throw PoseError(other, "a fetal pose starts from its lie (longitudinal, transverse, oblique or random)");
    return std::nullopt;
  }
  if (lie == "random") {
    if (other) throw PoseError(other, "lie random draws the whole pose from the seed: give no presentation, back or head side with it");
    return draw_pose(seed);
  }
  const auto unknown = [](const char* key, const std::string& what, const std::string& name, const std::vector<std::string>& names) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    return PoseError(key, "unknown " + what + " '" + name + "' (one of " + list + ")");
  };
  FetalLie l;
  if (!parse(lie, l)) throw unknown("lie", "lie", lie, requested_lie_names());
  FetalPose pose = default_pose(l);
  if (!presentation.empty() && !parse(presentation, pose.presentation))
    throw unknown("presentation", "presentation", presentation, presentation_names());
  if (!back.empty() && !parse(back, pose.back)) throw unknown("back", "back", back, back_names());
  if (!head_side.empty()) {
    if (l == FetalLie::longitudinal)
      throw PoseError("head_side", "a longitudinal lie has no head side (the head lies over the pelvis or in the fundus)");
    if (!parse(head_side, pose.head_side)) throw unknown("head_side", "head side", head_side, side_names());
  }
  if (const std::string why = why_invalid(pose); !why.empty()) {
    const bool lie_and_presentation = (pose.lie == FetalLie::transverse) != (pose.presentation == FetalPresentation::shoulder);
    throw PoseError(lie_and_presentation ? (presentation.empty() ? "lie" : "presentation") : (back.empty() ? "lie" : "back"), why);
  }
  return pose;
}

std::string describe(const FetalPose& pose) {
  std::string text = std::string(to_string(pose.lie)) + " lie, " + to_string(pose.presentation) + " presentation, back " +
                     to_string(pose.back);
  if (pose.lie != FetalLie::longitudinal) text += std::string(", head on the mother's ") + to_string(pose.head_side);
  return text;
}

}  // namespace fetouch::config
