#include "app/study/hard_cases_report.h"

#include <cstdio>
#include <sstream>

#include "app/json_writer.h"
#include "app/output_guard.h"
#include "app/study/study_table.h"

namespace fetouch::app {

bool write_hard_cases_outputs(const std::filesystem::path& out, const std::string& tissue, const std::string& title,
                              const std::string& setting, const std::vector<HardCaseOutcome>& outcomes, bool json_on_stdout) {
  bool all_sound = true;
  StudyTable table;
  table.columns = {"case", "expected", "sound", "converged", "newton_iterations", "cuts", "rollbacks", "min_j", "finite",
                   "reached_m", "seconds"};
  for (const HardCaseOutcome& c : outcomes) {
    all_sound = all_sound && c.sound;
    const auto cell = [](std::string text) {
      for (char& ch : text) ch = ch == ',' ? ';' : ch;
      return text;
    };
    table.rows.push_back({cell(c.name), cell(c.expected), c.sound ? "1" : "0", c.converged ? "1" : "0", std::to_string(c.iterations),
                          std::to_string(c.cuts), std::to_string(c.rollbacks), format_number(c.min_j), c.finite ? "1" : "0",
                          format_number(c.reached), format_number(c.seconds)});
  }
  write_csv(table, out / "table.csv");
  std::ostringstream md;
  md << "# Hard cases: " << title << "\n\n" << setting << "\n\n"
     << "| case | expected | result | Newton iterations | cuts | rollbacks | smallest J | NaN | time (s) | sound |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const HardCaseOutcome& c : outcomes) {
    char j[32];
    std::snprintf(j, sizeof j, "%.3f", c.min_j);
    char t[32];
    std::snprintf(t, sizeof t, "%.2f", c.seconds);
    md << "| " << c.name << " | " << c.expected << " | " << c.result << " | " << c.iterations << " | " << c.cuts << " | "
       << c.rollbacks << " | " << j << " | " << (c.finite ? "none" : "**yes**") << " | " << t << " | "
       << (c.sound ? "yes" : "**NO**") << " |\n";
  }
  md << "\n" << (all_sound ? "Every case is sound." : "**Not every case is sound.**") << "\n";
  write_text_file(out / "report.md", md.str());
  std::ostringstream json_text;
  JsonWriter json(json_text);
  json.begin_object().key("tissue").value(tissue).key("sound").value(all_sound);
  json.key("cases").begin_array();
  for (const HardCaseOutcome& c : outcomes)
    json.begin_object().key("case").value(c.name).key("expected").value(c.expected).key("sound").value(c.sound)
        .key("converged").value(c.converged).key("result").value(c.result).key("newton_iterations").value(c.iterations)
        .key("cuts").value(c.cuts).key("rollbacks").value(c.rollbacks).key("min_j").value(c.min_j).key("finite").value(c.finite)
        .key("seconds").value(c.seconds).end_object();
  json.end_array().end_object();
  json_text << "\n";
  if (!publish_json(out, json_text.str(), json_on_stdout)) {
    for (const HardCaseOutcome& c : outcomes)
      std::printf("%-50s %-9s %4d it %3d cuts  min J %.3f  %6.2f s  %s\n", c.name.c_str(), c.sound ? "sound" : "NOT SOUND",
                  c.iterations, c.cuts, c.min_j, c.seconds, c.result.c_str());
    std::printf("%s; wrote %s\n", all_sound ? "every case is sound" : "NOT every case is sound", (out / "report.md").string().c_str());
  }
  return all_sound;
}

}  // namespace fetouch::app
