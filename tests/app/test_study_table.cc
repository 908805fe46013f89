// The studies' arithmetic against answers worked out by hand: the Pareto set of a small trade-off,
// a power law fitted to points on one, and a table written and read back.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "app/session.h"
#include "app/study/study_table.h"

namespace fetouch::app {
namespace {

TEST(StudyTable, ParetoSetOfAHandWorkedTradeOff) {
  // (cost, error): a (1, 9) and e (5, 1) are ends of the front; b (2, 5) and d (4, 2) lie on it;
  // c (3, 6) is dominated by b; f (5, 3) by e (same cost, worse error); g ties b exactly: both stay;
  // a NaN row takes no part.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> cost{1, 2, 3, 4, 5, 5, 2, nan};
  const std::vector<double> error{9, 5, 6, 2, 1, 3, 5, 0.1};
  const std::vector<bool> expected{true, true, false, true, true, false, true, false};
  EXPECT_EQ(pareto_optimal(cost, error), expected);
}

TEST(StudyTable, PowerLawFitRecoversItsExponent) {
  std::vector<double> x, y;
  for (double dofs : {1e3, 8e3, 6.4e4}) x.push_back(dofs), y.push_back(3.0 * std::pow(dofs, -0.75));
  const PowerFit fit = fit_power_law(x, y);
  EXPECT_EQ(fit.points, 3);
  EXPECT_NEAR(fit.slope, -0.75, 1e-12);
  EXPECT_NEAR(fit.coefficient, 3.0, 1e-9);
  EXPECT_TRUE(std::isnan(fit_power_law({1.0}, {2.0}).slope));  // one point fits nothing
  EXPECT_EQ(fit_power_law({1, 2, 0}, {1, 0.5, 7}).points, 2);  // x = 0 has no logarithm
}

TEST(StudyTable, WrittenAndReadBackExactly) {
  const auto file = std::filesystem::temp_directory_path() / "fetouch_study_table_test.csv";
  StudyTable t;
  t.columns = {"axis", "x", "empty"};
  t.rows = {{"mesh", format_number(0.1 + 0.2), ""}, {"rate", format_number(1.0 / 3), format_number(1e-300)}};
  write_csv(t, file);
  const StudyTable back = read_csv(file);
  EXPECT_EQ(back.columns, t.columns);
  ASSERT_EQ(back.rows.size(), 2u);
  EXPECT_EQ(back.number(0, "x"), 0.1 + 0.2);
  EXPECT_EQ(back.number(1, "x"), 1.0 / 3);
  EXPECT_EQ(back.number(1, "empty"), 1e-300);
  EXPECT_TRUE(std::isnan(back.number(0, "empty")));
  EXPECT_TRUE(std::isnan(back.number(0, "axis")));
  std::filesystem::remove(file);
}

TEST(StudyTable, PercentileByNearestRank) {
  EXPECT_EQ(percentile({5, 1, 4, 2, 3}, 0.5), 3);
  EXPECT_EQ(percentile({5, 1, 4, 2, 3}, 0.99), 5);
  EXPECT_EQ(percentile({5, 1, 4, 2, 3}, 0), 1);
  EXPECT_EQ(percentile({}, 0.5), 0);
}

}  // namespace
}  // namespace fetouch::app
