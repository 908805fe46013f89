#include "config/diagnostics.h"

#include <algorithm>
#include <cctype>
#include <sstream>

namespace fetouch::config {

std::string Diagnostic::format() const {
  std::ostringstream out;
  // A path of hundreds of characters is shown by its two ends: the message stays one line.
  out << (file.size() <= 200 ? file : file.substr(0, 80) + "..." + file.substr(file.size() - 80));
  if (line > 0) out << ':' << line << ':' << column;
  out << ": " << (severity == Severity::error ? "error" : "warning") << ": ";
  if (!key.empty()) out << key << ": ";
  out << message;
  return out.str();
}

namespace {
std::string summarise(const std::vector<Diagnostic>& diagnostics) {
  std::string text;
  for (const auto& d : diagnostics) {
    if (!text.empty()) text += '\n';
    text += d.format();
  }
  return text;
}
}  // namespace

SceneError::SceneError(std::vector<Diagnostic> diagnostics)
    : std::runtime_error(summarise(diagnostics)), diagnostics_(std::move(diagnostics)) {}

int edit_distance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      const int cost = std::tolower(a[i - 1]) == std::tolower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  // A typo is a few edits away; a third of the word's length keeps short keys from matching anything.
  const int limit = std::max(2, static_cast<int>(word.size()) / 3);
  std::string best;
  int best_distance = limit + 1;
  for (const auto& candidate : candidates) {
    int distance = edit_distance(word, candidate);
    // A key written without its unit suffix ("youngs_modulus" for "youngs_modulus_pa") is a typo too.
    if (candidate.rfind(word + "_", 0) == 0 && word.size() >= 4) distance = std::min(distance, 1);
    if (distance < best_distance) {
      best_distance = distance;
      best = candidate;
    }
  }
  return best;
}

}  // namespace fetouch::config
