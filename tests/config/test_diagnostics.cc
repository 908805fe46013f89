#include <gtest/gtest.h>

#include "config/diagnostics.h"

namespace fetouch::config {
namespace {

// Textbook values of the optimal-string-alignment distance.
TEST(EditDistance, KnownValues) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);  // two substitutions and an insertion
  EXPECT_EQ(edit_distance("", "abc"), 3);
  EXPECT_EQ(edit_distance("abc", "abc"), 0);
  EXPECT_EQ(edit_distance("ab", "ba"), 1);  // one adjacent swap
  EXPECT_EQ(edit_distance("ca", "abc"), 3);  // OSA, unlike full Damerau-Levenshtein (2)
  EXPECT_EQ(edit_distance("Hold", "hold"), 0);  // keys differing only in case are the same typo
}

TEST(ClosestMatch, SuggestsTyposButNotUnrelatedWords) {
  const std::vector<std::string> keys{"youngs_modulus_pa", "poisson_ratio", "density_kg_per_m3"};
  EXPECT_EQ(closest_match("poison_ratio", keys), "poisson_ratio");
  EXPECT_EQ(closest_match("youngs_modulus", keys), "youngs_modulus_pa");  // unit suffix left out
  EXPECT_EQ(closest_match("colour", keys), "");
  EXPECT_EQ(closest_match("fho", {"zoh", "foh"}), "foh");
}

TEST(Diagnostic, FormatsFileLineColumnKeyMessage) {
  Diagnostic d;
  d.file = "scene.yaml";
  d.line = 12;
  d.column = 5;
  d.key = "material.poisson_ratio";
  d.message = "0.5 is out of range";
  EXPECT_EQ(d.format(), "scene.yaml:12:5: error: material.poisson_ratio: 0.5 is out of range");
  d.severity = Diagnostic::Severity::warning;
  d.line = 0;
  EXPECT_EQ(d.format(), "scene.yaml: warning: material.poisson_ratio: 0.5 is out of range");
}

}  // namespace
}  // namespace fetouch::config
