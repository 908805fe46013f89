// How the phantom's fetus lies in the uterus, in the words obstetrics uses for what the four Leopold
// maneuvers find: the lie (the fetus's long axis against the mother's), the presentation (what lies
// over the pelvis) and the position (where the fetal back faces).
//
// The uterus frame is the phantom's (imaging/phantom.h): x towards the fundus (the mother's head),
// -x towards the pelvis; z anterior (the mother's belly, the side the probe and the hands are on);
// y = z × x, the mother's right.
//
//   lie           head direction (cephalic / breech)                        back may face
//   longitudinal  -x / +x                                                   left, right, anterior, posterior
//                                                                           and the four between them
//   transverse    -y or +y (the head on the mother's left or right)         anterior, posterior, superior
//                 (shoulder presentation only)                              (fundus), inferior (pelvis)
//   oblique       45° between: (-x or +x) and (-y or +y)                    any of those not along the axis
//
// A back direction is taken square to the head's (its component along the axis removed); a back
// that lies within 60° of the axis (left or right in a transverse lie) is refused.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fetouch::config {

enum class FetalLie { longitudinal, transverse, oblique };
enum class FetalPresentation { cephalic, breech, shoulder };
enum class FetalBack { left, right, anterior, posterior, left_anterior, right_anterior, left_posterior, right_posterior, superior, inferior };
enum class MaternalSide { left, right };

struct FetalPose {
  FetalLie lie = FetalLie::longitudinal;
  FetalPresentation presentation = FetalPresentation::cephalic;
  FetalBack back = FetalBack::left_anterior;  // left occiput anterior, the commonest at term
  MaternalSide head_side = MaternalSide::left;  // transverse and oblique lies only
};

// The names scenes and `fetouch phantom` use ("longitudinal", "left_anterior", ...).
const std::vector<std::string>& lie_names();
const std::vector<std::string>& presentation_names();
const std::vector<std::string>& back_names();
const std::vector<std::string>& side_names();
// What a scene's `lie` or `fetouch phantom --lie` take: lie_names() and "random".
const std::vector<std::string>& requested_lie_names();
const char* to_string(FetalLie value);
const char* to_string(FetalPresentation value);
const char* to_string(FetalBack value);
const char* to_string(MaternalSide value);
bool parse(const std::string& name, FetalLie& out);
bool parse(const std::string& name, FetalPresentation& out);
bool parse(const std::string& name, FetalBack& out);
bool parse(const std::string& name, MaternalSide& out);

// The fetus's head and back directions in the uterus frame (unit, square to each other). Throws
// std::invalid_argument saying why for a pose a fetus cannot take (a transverse lie that does not
// present the shoulder, or the reverse; a back within 60 degrees of the fetal axis).
struct FetalAxes {
  std::array<double, 3> head{0, 0, 0}, back{0, 0, 0};
};
FetalAxes fetal_axes(const FetalPose& pose);

// Every valid pose (the head's side only where the lie has one): what a test or a study sweeps.
std::vector<FetalPose> every_pose();
// One of every_pose(), drawn uniformly from `seed` (the same seed, the same pose).
FetalPose draw_pose(std::uint32_t seed);

// A pose refused: what() says why, key() which of the names is at fault ("lie", "presentation",
// "back" or "head_side", as the scene's keys are called).
class PoseError : public std::invalid_argument {
 public:
  PoseError(const char* key, const std::string& why) : std::invalid_argument(why), key_(key) {}
  const char* key() const { return key_; }

 private:
  const char* key_;
};

// The pose a scene or a command line asks for, by names (empty: not given); none when no name is
// given. `lie` alone gives that lie's usual presentation and back (cephalic and left_anterior, or
// shoulder and anterior for a transverse lie), the others override them; lie "random" draws the
// whole pose from `seed` and takes nothing else. Throws PoseError saying which name is unknown,
// which was given without a lie or beside "random", or why the pose is not valid.
std::optional<FetalPose> requested_pose(const std::string& lie, const std::string& presentation, const std::string& back,
                         const std::string& head_side, std::uint32_t seed);

// "transverse lie, shoulder presentation, back superior, head on the mother's left"
std::string describe(const FetalPose& pose);

}  // namespace fetouch::config
