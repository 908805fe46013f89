#include "imaging/fetal_biometry.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace fetouch::imaging {

namespace {

// The measure x (cm) with a + b x + c x^2 = weeks, times 10 (mm).
double solve_mm(double a, double b, double c, double weeks) {
  if (!(weeks >= kEarliestWeeks && weeks <= kLatestWeeks))
    throw std::invalid_argument("gestational age " + std::to_string(weeks) + " weeks is outside Hadlock's 14 to 42");
  return 10 * (-b + std::sqrt(b * b - 4 * c * (a - weeks))) / (2 * c);
}

}  // namespace

double biparietal_diameter_mm(double weeks) { return solve_mm(9.54, 1.482, 0.1676, weeks); }
double abdominal_circumference_mm(double weeks) { return solve_mm(8.14, 0.753, 0.0036, weeks); }
double femur_length_mm(double weeks) { return solve_mm(10.35, 2.460, 0.170, weeks); }

FetalGrowth growth_at(double weeks) {
  // The phantom's nominal fetus (imaging/phantom.cc): a head 2 x 16 mm across, a trunk whose cross
  // section has semi-axes 15 and 14 mm (Ramanujan's perimeter: 91.1 mm).
  const double nominal_bpd_mm = 32, a = 15, b = 14;
  const double nominal_girth_mm = M_PI * (3 * (a + b) - std::sqrt((3 * a + b) * (a + 3 * b)));
  FetalGrowth g;
  g.head = biparietal_diameter_mm(weeks) / nominal_bpd_mm;
  g.trunk_girth = abdominal_circumference_mm(weeks) / nominal_girth_mm;
  g.limbs = femur_length_mm(weeks) / femur_length_mm(kPhantomWeeks);
  g.trunk_length = g.uterus = g.head;
  return g;
}

}  // namespace fetouch::imaging
