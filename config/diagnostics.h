// Messages about a scene file, each pinned to file:line:column and the dotted key it concerns.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace fetouch::config {

struct Diagnostic {
  enum class Severity { error, warning };
  Severity severity = Severity::error;
  std::string file;
  int line = 0;    // 1-based; 0 when the message concerns the whole file
  int column = 0;  // 1-based
  std::string key;      // dotted path such as "material.poisson_ratio" or "probes[1].name"
  std::string message;  // what is wrong and what would be accepted

  // "scene.yaml:12:5: error: material.poisson_ratio: 0.5 is out of range; expected ..."
  std::string format() const;
};

// Thrown by the loader when a scene has at least one error; holds every error and warning found.
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(std::vector<Diagnostic> diagnostics);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

// The closest of `candidates` to `word` when it is close enough to be a likely typo, else "".
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

// Optimal-string-alignment distance: insertions, deletions, substitutions, adjacent swaps.
int edit_distance(const std::string& a, const std::string& b);

}  // namespace fetouch::config
