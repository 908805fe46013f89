// Fetal size against gestational age, from Hadlock's regressions of menstrual age on each measure
// (Hadlock FP, Deter RL, Harrist RB, Park SK: Estimating fetal age: computer-assisted analysis of
// multiple fetal growth parameters. Radiology 152:497-501, 1984; measures in cm, age in weeks):
//   BPD: GA = 9.54 + 1.482 BPD + 0.1676 BPD^2
//   AC:  GA = 8.14 + 0.753 AC + 0.0036 AC^2
//   FL:  GA = 10.35 + 2.460 FL + 0.170 FL^2
// solved here for the measure at a given age (the positive root), in mm. They were fitted from 14
// to 42 weeks; outside that range the functions refuse.
//
// The phantom's fetus without an age is about 16 weeks by these: its head's biparietal diameter is
// 32 mm (Hadlock: 32.0 mm at 16 weeks), its trunk's girth about 91 mm (100 mm) and its thigh about
// 20 mm long (a femur of 20.2 mm).
#pragma once

namespace fetouch::imaging {

constexpr double kPhantomWeeks = 16;
constexpr double kEarliestWeeks = 14, kLatestWeeks = 42;

// Throw std::invalid_argument for an age outside [kEarliestWeeks, kLatestWeeks].
double biparietal_diameter_mm(double weeks);
double abdominal_circumference_mm(double weeks);
double femur_length_mm(double weeks);

// How much each part of the phantom's nominal fetus, and the uterus around it, is scaled to reach
// an age: the head to Hadlock's biparietal diameter, the trunk's girth to the abdominal
// circumference, the limbs by the femur length from 16 weeks, and the trunk's length, the uterus
// and the volume as the head (the fetus's length grows as its head does: crown-rump about 3.1
// times from 16 weeks to term, the head 3.0). At 16 weeks the head and limbs stay, the trunk is
// 9 % thicker (the nominal trunk is thinner than Hadlock's 100 mm).
struct FetalGrowth {
  double head = 1, trunk_length = 1, trunk_girth = 1, limbs = 1, uterus = 1;
};
FetalGrowth growth_at(double weeks);

}  // namespace fetouch::imaging
