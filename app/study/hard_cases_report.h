// What `fetouch study hard-cases` writes (app/study/hard_cases_study.cc runs the cases): each case's
// outcome as STUDY/table.csv, STUDY/report.md, the JSON summary and the lines on stdout.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fetouch::app {

struct HardCaseOutcome {
  std::string name, expected, result, failure;
  bool sound = false, converged = false;
  int iterations = 0, cuts = 0, rollbacks = 0;
  double min_j = 0, seconds = 0, reached = 0;
  bool finite = true;
};

// `tissue`: the JSON's name for it; `title` the report's; `setting` the report's paragraph on where
// and how the cases press. Returns whether every case is sound.
bool write_hard_cases_outputs(const std::filesystem::path& out, const std::string& tissue, const std::string& title,
                              const std::string& setting, const std::vector<HardCaseOutcome>& outcomes, bool json_on_stdout);

}  // namespace fetouch::app
