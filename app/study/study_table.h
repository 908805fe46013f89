// What the studies share: their tables (CSV, read back by tests), the Pareto set of a trade-off,
// a power-law fit, and the options every study takes.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fetouch::app {

// A table of named columns; cells are text (numbers written with full precision).
struct StudyTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const;  // -1: none
  double number(std::size_t row, const std::string& name) const;  // NaN when empty or not a number
  std::string text(std::size_t row, const std::string& name) const;  // empty when no such column
};

std::string format_number(double value);  // shortest text that reads back exactly; empty for NaN
void write_csv(const StudyTable& table, const std::filesystem::path& file);
// Throws std::runtime_error naming the file and line of a malformed row.
StudyTable read_csv(const std::filesystem::path& file);

// The rows of (cost, error) that no other row dominates (another row no worse in both and better
// in one), both to be minimised; rows with a NaN take no part.
std::vector<bool> pareto_optimal(const std::vector<double>& cost, const std::vector<double>& error);

// Least squares of log y = log c + slope log x over the points with x, y > 0; slope NaN for fewer
// than two.
struct PowerFit {
  double slope = 0, coefficient = 0;
  int points = 0;
};
PowerFit fit_power_law(const std::vector<double>& x, const std::vector<double>& y);

// Writes DIR/study.json and, with --json, prints it; returns whether it printed it (the caller
// prints its plain summary otherwise).
bool publish_json(const std::filesystem::path& out, const std::string& json_text, bool print);

struct StudyOptions {
  std::string scene, out = "fetouch-study";
  bool json = false, quick = false;
  int threads = 1;
};

}  // namespace fetouch::app
