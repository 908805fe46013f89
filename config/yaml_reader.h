// Checked reading of YAML mappings: every value is read through a MapView that knows the keys it
// accepts, so unknown keys, duplicates, wrong types and out-of-range values all become diagnostics
// with file:line:column and a dotted key. Reading goes on after an error, so one run of
// `fetouch check` reports every problem in a file, not only the first.
#pragma once

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/diagnostics.h"
#include "config/scene.h"

namespace fetouch::config::detail {

class Reader {
 public:
  Reader(std::string file_label, std::filesystem::path base_dir)
      : file_label_(std::move(file_label)), base_dir_(std::move(base_dir)) {}

  void error(const YAML::Mark& mark, const std::string& key, const std::string& message);
  void warning(const YAML::Mark& mark, const std::string& key, const std::string& message);
  bool has_errors() const;
  const std::filesystem::path& base_dir() const { return base_dir_; }
  std::vector<Diagnostic>& diagnostics() { return diagnostics_; }

 private:
  void add(Diagnostic::Severity, const YAML::Mark&, const std::string&, const std::string&);
  std::string file_label_;
  std::filesystem::path base_dir_;
  std::vector<Diagnostic> diagnostics_;
};

// A closed or open interval for a number, printed in messages as "(-1, 0.5)" or "[0, 1)".
struct Range {
  double low = -1e308;
  double high = 1e308;
  bool low_open = false;
  bool high_open = false;
  const char* why = nullptr;  // what the range means, with units ("0.1 mm to 2 m: ...")
  std::string describe() const;
  std::string describe_bounds() const;
  bool contains(double value) const;

  static Range positive() { return {0, 1e308, true, false}; }
  static Range non_negative() { return {0, 1e308, false, false}; }
  static Range any() { return {}; }
};

enum class Need { optional, required };

template <class E>
using Choices = std::vector<std::pair<std::string, E>>;

// One key of a mapping as written.
//
// Careful with YAML::Node: `a = b` on nodes writes b's value *into the node a refers to*, changing
// the document. Entries therefore copy by rebinding (Node::reset), never by node assignment.
struct Entry {
  Entry() = default;
  Entry(const Entry& other) = default;
  Entry& operator=(const Entry& other) {
    present = other.present;
    value.reset(other.value);
    key_mark = other.key_mark;
    value_mark = other.value_mark;
    path = other.path;
    return *this;
  }

  bool present = false;
  YAML::Node value;
  YAML::Mark key_mark;
  YAML::Mark value_mark;  // the key's mark when the value has none (an empty value)
  std::string path;       // dotted key path
};

class MapView {
 public:
  // Reports `node` not being a mapping, unknown keys (with the closest valid key) and duplicates.
  // `where` is the mapping's own key ("material:"): missing keys are reported there.
  MapView(Reader& reader, const YAML::Node& node, std::string path, const YAML::Mark& where,
          std::vector<std::string> allowed);

  bool valid() const { return valid_; }
  bool has(const std::string& key) const;
  Entry entry(const std::string& key) const;
  const std::string& path() const { return path_; }
  const YAML::Mark& mark() const { return mark_; }
  Reader& reader() const { return reader_; }
  std::string child_path(const std::string& key) const;

  // Each returns true when the key is present and its value valid; `out` is left alone otherwise.
  bool number(const std::string& key, double& out, const Range& range, Need need = Need::optional);
  bool integer(const std::string& key, int& out, const Range& range, Need need = Need::optional);
  bool boolean(const std::string& key, bool& out, Need need = Need::optional);
  bool text(const std::string& key, std::string& out, Need need = Need::optional);
  // Each component within `range` (reported at the component).
  bool vec3(const std::string& key, Vec3& out, Need need = Need::optional, const Range& range = Range::any());
  // A file or folder that must exist; stored absolute, resolved against the scene's folder.
  bool existing_path(const std::string& key, std::filesystem::path& out, Need need,
                     const std::vector<std::string>& extensions, bool allow_directory = false);

  template <class E>
  bool choice(const std::string& key, E& out, const Choices<E>& choices, Need need = Need::optional);

  // Reports a missing key as an error at the mapping, with `why` explaining why it is needed.
  void require(const std::string& key, const std::string& why = "");

 private:
  bool present_or_report(const std::string& key, Need need);
  bool choice_index(const std::string& key, const std::vector<std::string>& names, size_t& index,
                    Need need);

  Reader& reader_;
  std::string path_;
  YAML::Mark mark_;
  bool valid_ = false;
  std::map<std::string, Entry> entries_;
};

// A non-empty list of distinct, non-empty names (`what` names one in messages: "volume regions
// such as [fluid, fetus]"); each problem reported at its entry. The names read, bad ones left out.
std::vector<std::string> read_name_list(Reader& reader, const Entry& list, const std::string& what);

// The offset of the first NUL byte or malformed UTF-8 sequence in `text`, if any.
std::optional<std::size_t> first_non_text_byte(const std::string& text);
// A YAML mark (0-based line and column) for a byte offset of `text`.
YAML::Mark mark_at(const std::string& text, std::size_t offset);

// The value of an entry read as a scalar of the given kind, with its own diagnostics.
std::optional<double> read_number(Reader& reader, const Entry& entry);
std::optional<std::string> read_text(Reader& reader, const Entry& entry);

// "a mapping", "a list", "the text \"abc\"", "a number (3.5)" for messages about wrong types.
std::string describe_node(const YAML::Node& node);

template <class E>
bool MapView::choice(const std::string& key, E& out, const Choices<E>& choices, Need need) {
  std::vector<std::string> names;
  for (const auto& choice : choices) names.push_back(choice.first);
  size_t index = 0;
  if (!choice_index(key, names, index, need)) return false;
  out = choices[index].second;
  return true;
}

}  // namespace fetouch::config::detail
