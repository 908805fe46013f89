#include "app/study/study_table.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "app/output_guard.h"

namespace fetouch::app {

int StudyTable::column(const std::string& name) const {
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) return static_cast<int>(c);
  return -1;
}

double StudyTable::number(std::size_t row, const std::string& name) const {
  const int c = column(name);
  if (c < 0 || row >= rows.size() || rows[row][static_cast<std::size_t>(c)].empty())
    return std::numeric_limits<double>::quiet_NaN();
  const std::string& text = rows[row][static_cast<std::size_t>(c)];
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() ? x : std::numeric_limits<double>::quiet_NaN();
}

std::string StudyTable::text(std::size_t row, const std::string& name) const {
  const int c = column(name);
  return c < 0 || row >= rows.size() ? std::string() : rows[row][static_cast<std::size_t>(c)];
}

std::string format_number(double value) {
  if (std::isnan(value)) return "";
  char text[32];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

void write_csv(const StudyTable& table, const std::filesystem::path& file) {
  std::ostringstream out;
  const auto line = [&out](const std::vector<std::string>& cells) {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (cells[c].find_first_of(",\"\n") != std::string::npos)
        throw std::invalid_argument("a study's table cell may not hold a comma or quote: " + cells[c]);
      out << (c ? "," : "") << cells[c];
    }
    out << "\n";
  };
  line(table.columns);
  for (const auto& row : table.rows) line(row);
  write_text_file(file, out.str());
}

StudyTable read_csv(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  StudyTable table;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    std::vector<std::string> cells;
    std::stringstream cells_text(text);
    std::string cell;
    while (std::getline(cells_text, cell, ',')) cells.push_back(cell);
    if (!text.empty() && text.back() == ',') cells.emplace_back();
    if (line == 1) {
      table.columns = cells;
      continue;
    }
    if (cells.size() != table.columns.size())
      throw std::runtime_error(file.string() + ":" + std::to_string(line) + ": " + std::to_string(cells.size()) +
                               " cells where the header has " + std::to_string(table.columns.size()));
    table.rows.push_back(std::move(cells));
  }
  return table;
}

bool publish_json(const std::filesystem::path& out, const std::string& json_text, bool print) {
  write_text_file(out / "study.json", json_text);
  if (print) std::fwrite(json_text.data(), 1, json_text.size(), stdout);
  return print;
}

std::vector<bool> pareto_optimal(const std::vector<double>& cost, const std::vector<double>& error) {
  const std::size_t n = cost.size();
  std::vector<bool> optimal(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(cost[i]) || std::isnan(error[i])) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < n && !dominated; ++j) {
      if (j == i || std::isnan(cost[j]) || std::isnan(error[j])) continue;
      dominated = cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i]);
    }
    optimal[i] = !dominated;
  }
  return optimal;
}

PowerFit fit_power_law(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  PowerFit fit;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0)) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    ++fit.points;
  }
  if (fit.points < 2 || sxx * fit.points - sx * sx <= 0) {
    fit.slope = std::numeric_limits<double>::quiet_NaN();
    return fit;
  }
  const double n = fit.points;
  fit.slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  fit.coefficient = std::exp((sy - fit.slope * sx) / n);
  return fit;
}

}  // namespace fetouch::app
