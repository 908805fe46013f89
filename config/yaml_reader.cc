#include "config/yaml_reader.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <limits>
#include <sstream>
#include <system_error>

namespace fetouch::config::detail {

namespace {

std::string join(const std::vector<std::string>& words) {
  std::string text;
  for (size_t i = 0; i < words.size(); ++i) {
    if (i > 0) text += (i + 1 == words.size()) ? " or " : ", ";
    text += words[i];
  }
  return text;
}

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// yaml-cpp tags plain scalars "?" and quoted ones "!": a quoted "5000" is text, not a number.
bool is_quoted(const YAML::Node& node) { return node.Tag() == "!"; }

}  // namespace

void Reader::add(Diagnostic::Severity severity, const YAML::Mark& mark, const std::string& key,
                 const std::string& message) {
  Diagnostic d;
  d.severity = severity;
  d.file = file_label_;
  d.line = mark.is_null() ? 0 : mark.line + 1;
  d.column = mark.is_null() ? 0 : mark.column + 1;
  d.key = key;
  d.message = message;
  diagnostics_.push_back(std::move(d));
}

void Reader::error(const YAML::Mark& mark, const std::string& key, const std::string& message) {
  add(Diagnostic::Severity::error, mark, key, message);
}

void Reader::warning(const YAML::Mark& mark, const std::string& key, const std::string& message) {
  add(Diagnostic::Severity::warning, mark, key, message);
}

bool Reader::has_errors() const {
  for (const auto& d : diagnostics_)
    if (d.severity == Diagnostic::Severity::error) return true;
  return false;
}

// The offset of the first NUL byte or malformed UTF-8 sequence, if any.
std::optional<std::size_t> first_non_text_byte(const std::string& text) {
  const auto* b = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned char c = b[i];
    if (c == 0) return i;
    const int extra = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xe ? 2 : (c >> 3) == 0x1e ? 3 : -1;
    if (extra < 0 || (extra == 1 && c < 0xc2) || i + static_cast<std::size_t>(extra) >= n + (extra == 0)) return i;
    for (int k = 1; k <= extra; ++k)
      if ((b[i + k] >> 6) != 0x2) return i;
    i += static_cast<std::size_t>(extra) + 1;
  }
  return std::nullopt;
}

// A YAML mark (0-based line and column) for a byte offset.
YAML::Mark mark_at(const std::string& text, std::size_t offset) {
  YAML::Mark mark;
  mark.pos = static_cast<int>(offset);
  mark.line = static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n'));
  const std::size_t line_start = text.rfind('\n', offset == 0 ? 0 : offset - 1);
  mark.column = static_cast<int>(line_start == std::string::npos || offset == 0 ? offset : offset - line_start - 1);
  return mark;
}

std::string Range::describe() const {
  const std::string bounds = describe_bounds();
  return why ? bounds + " (" + why + ")" : bounds;
}

std::string Range::describe_bounds() const {
  const bool has_low = low > -1e307, has_high = high < 1e307;
  if (has_low && !has_high) return std::string(low_open ? "> " : ">= ") + format_number(low);
  if (!has_low && has_high) return std::string(high_open ? "< " : "<= ") + format_number(high);
  if (!has_low && !has_high) return "any finite number";
  return std::string("in ") + (low_open ? "(" : "[") + format_number(low) + ", " +
         format_number(high) + (high_open ? ")" : "]");
}

bool Range::contains(double value) const {
  if (low_open ? !(value > low) : !(value >= low)) return false;
  if (high_open ? !(value < high) : !(value <= high)) return false;
  return true;
}

std::string describe_node(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map: return "a mapping";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Null: return "nothing";
    case YAML::NodeType::Scalar:
      if (is_quoted(node)) return "the text \"" + node.Scalar() + "\"";
      return "'" + node.Scalar() + "'";
    default: return "an undefined value";
  }
}

std::optional<double> read_number(Reader& reader, const Entry& entry) {
  const YAML::Node& node = entry.value;
  if (!node.IsScalar() || is_quoted(node)) {
    reader.error(entry.value_mark, entry.path, "expected a number, got " + describe_node(node));
    return std::nullopt;
  }
  // An explicit tag other than a number's (`!!str 5000`, `!pascal 5000`) says it is not a number.
  const std::string& tag = node.Tag();
  if (tag != "?" && tag != "" && tag != "tag:yaml.org,2002:float" && tag != "tag:yaml.org,2002:int") {
    reader.error(entry.value_mark, entry.path, "expected a number, got a value tagged " + tag + "; write the number without a tag");
    return std::nullopt;
  }
  const std::string& text = node.Scalar();
  try {
    size_t used = 0;
    const double value = std::stod(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    if (!std::isfinite(value)) {
      reader.error(entry.value_mark, entry.path, "expected a finite number, got '" + text + "'");
      return std::nullopt;
    }
    return value;
  } catch (const std::exception&) {
    reader.error(entry.value_mark, entry.path, "expected a number, got " + describe_node(node));
    return std::nullopt;
  }
}

std::vector<std::string> read_name_list(Reader& reader, const Entry& list, const std::string& what) {
  std::vector<std::string> names;
  if (!list.value.IsSequence() || list.value.size() == 0) {
    reader.error(list.value_mark, list.path, "expected a list of " + what + ", found " + describe_node(list.value));
    return names;
  }
  for (std::size_t i = 0; i < list.value.size(); ++i) {
    Entry item = list;
    item.value.reset(list.value[i]);
    item.value_mark = list.value[i].Mark();
    item.path = list.path + "[" + std::to_string(i) + "]";
    const std::optional<std::string> name = read_text(reader, item);
    if (!name) continue;
    if (name->empty())
      reader.error(item.value_mark, item.path, "expected a name or number, found an empty text");
    else if (std::count(names.begin(), names.end(), *name))
      reader.error(item.value_mark, item.path, "'" + *name + "' is listed twice");
    else
      names.push_back(*name);
  }
  return names;
}

std::optional<std::string> read_text(Reader& reader, const Entry& entry) {
  if (!entry.value.IsScalar()) {
    reader.error(entry.value_mark, entry.path, "expected text, got " + describe_node(entry.value));
    return std::nullopt;
  }
  return entry.value.Scalar();
}

MapView::MapView(Reader& reader, const YAML::Node& node, std::string path, const YAML::Mark& where,
                 std::vector<std::string> allowed)
    : reader_(reader), path_(std::move(path)), mark_(where.is_null() ? node.Mark() : where) {
  const std::string name = path_.empty() ? "the scene" : path_;
  if (!node.IsMap()) {
    reader_.error(mark_, path_, "expected a mapping of keys (" + join(allowed) + "), got " +
                                    describe_node(node));
    return;
  }
  valid_ = true;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const YAML::Node key = it->first;
    const YAML::Mark key_mark = key.Mark();
    if (!key.IsScalar()) {
      reader_.error(key_mark, path_, "a key must be a plain word, got " + describe_node(key));
      continue;
    }
    const std::string word = key.Scalar();
    const std::string child = child_path(word);
    bool known = false;
    for (const auto& a : allowed) known = known || a == word;
    if (!known) {
      std::string message = "unknown key '" + word + "' in " + name;
      const std::string suggestion = closest_match(word, allowed);
      if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
      else message += "; valid keys are " + join(allowed);
      reader_.error(key_mark, child, message);
      continue;
    }
    if (auto previous = entries_.find(word); previous != entries_.end()) {
      reader_.error(key_mark, child,
                    "duplicate key '" + word + "' (first written at line " +
                        std::to_string(previous->second.key_mark.line + 1) +
                        "); write each key once");
      continue;
    }
    Entry entry;
    entry.present = true;
    entry.value.reset(it->second);
    entry.key_mark = key_mark;
    // An empty value ("key:") carries the mark of whatever follows it; point at the key instead.
    entry.value_mark =
        it->second.IsNull() || it->second.Mark().is_null() ? key_mark : it->second.Mark();
    entry.path = child;
    entries_.emplace(word, std::move(entry));
  }
}

std::string MapView::child_path(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

bool MapView::has(const std::string& key) const { return entries_.count(key) > 0; }

Entry MapView::entry(const std::string& key) const {
  auto it = entries_.find(key);
  if (it != entries_.end()) return it->second;
  Entry missing;
  missing.key_mark = mark_;
  missing.value_mark = mark_;
  missing.path = child_path(key);
  return missing;
}

void MapView::require(const std::string& key, const std::string& why) {
  if (!valid_ || has(key)) return;
  std::string message = "missing required key '" + key + "'";
  if (!why.empty()) message += " (" + why + ")";
  reader_.error(mark_, child_path(key), message);
}

bool MapView::present_or_report(const std::string& key, Need need) {
  if (has(key)) return true;
  if (need == Need::required) require(key);
  return false;
}

bool MapView::number(const std::string& key, double& out, const Range& range, Need need) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  auto value = read_number(reader_, e);
  if (!value) return false;
  if (!range.contains(*value)) {
    reader_.error(e.value_mark, e.path,
                  format_number(*value) + " is out of range; expected a number " + range.describe());
    return false;
  }
  out = *value;
  return true;
}

bool MapView::integer(const std::string& key, int& out, const Range& range, Need need) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  auto value = read_number(reader_, e);
  if (!value) return false;
  if (*value != std::floor(*value) || std::abs(*value) > std::numeric_limits<int>::max()) {
    reader_.error(e.value_mark, e.path, "expected a whole number, got " + describe_node(e.value));
    return false;
  }
  if (!range.contains(*value)) {
    reader_.error(e.value_mark, e.path,
                  format_number(*value) + " is out of range; expected a whole number " +
                      range.describe());
    return false;
  }
  out = static_cast<int>(*value);
  return true;
}

bool MapView::boolean(const std::string& key, bool& out, Need need) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  bool value = false;
  if (!e.value.IsScalar() || is_quoted(e.value) || !YAML::convert<bool>::decode(e.value, value)) {
    reader_.error(e.value_mark, e.path, "expected true or false, got " + describe_node(e.value));
    return false;
  }
  out = value;
  return true;
}

bool MapView::text(const std::string& key, std::string& out, Need need) {
  if (!present_or_report(key, need)) return false;
  auto value = read_text(reader_, entry(key));
  if (!value) return false;
  out = *value;
  return true;
}

bool MapView::vec3(const std::string& key, Vec3& out, Need need, const Range& range) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  if (!e.value.IsSequence() || e.value.size() != 3) {
    reader_.error(e.value_mark, e.path,
                  "expected a list of three numbers [x, y, z], got " + describe_node(e.value) +
                      (e.value.IsSequence() ? " of " + std::to_string(e.value.size()) : ""));
    return false;
  }
  Vec3 v{};
  for (size_t i = 0; i < 3; ++i) {
    Entry component = e;
    component.value.reset(e.value[i]);
    component.value_mark = e.value[i].Mark().is_null() ? e.value_mark : e.value[i].Mark();
    component.path = e.path + "[" + std::to_string(i) + "]";
    auto value = read_number(reader_, component);
    if (!value) return false;
    if (!range.contains(*value)) {
      reader_.error(component.value_mark, component.path,
                    format_number(*value) + " is out of range; expected a number " + range.describe());
      return false;
    }
    v[i] = *value;
  }
  out = v;
  return true;
}

bool MapView::existing_path(const std::string& key, std::filesystem::path& out, Need need,
                            const std::vector<std::string>& extensions, bool allow_directory) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  auto written = read_text(reader_, e);
  if (!written) return false;
  if (written->empty()) {
    reader_.error(e.value_mark, e.path, "expected a file name, got nothing");
    return false;
  }
  std::filesystem::path path(*written);
  if (path.is_relative()) path = reader_.base_dir() / path;
  path = path.lexically_normal();
  std::error_code ec;
  const bool is_directory = std::filesystem::is_directory(path, ec);
  if (!std::filesystem::exists(path, ec)) {
    reader_.error(e.value_mark, e.path,
                  "file not found: '" + *written + "' (looked for " + path.string() +
                      "; relative names are relative to the scene file's folder)");
    return false;
  }
  if (is_directory && !allow_directory) {
    reader_.error(e.value_mark, e.path, "'" + *written + "' is a folder; expected a file");
    return false;
  }
  if (!is_directory && !extensions.empty()) {
    std::string name = path.filename().string();
    bool matched = false;
    for (const auto& ext : extensions)
      matched = matched || (name.size() > ext.size() &&
                            name.compare(name.size() - ext.size(), ext.size(), ext) == 0);
    if (!matched) {
      reader_.error(e.value_mark, e.path,
                    "'" + *written + "' has an unsupported extension; expected " + join(extensions));
      return false;
    }
  }
  out = path;
  return true;
}

bool MapView::choice_index(const std::string& key, const std::vector<std::string>& names,
                           size_t& index, Need need) {
  if (!present_or_report(key, need)) return false;
  const Entry e = entry(key);
  auto written = read_text(reader_, e);
  if (!written) return false;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == *written) {
      index = i;
      return true;
    }
  }
  std::string message = "'" + *written + "' is not one of " + join(names);
  const std::string suggestion = closest_match(*written, names);
  if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
  reader_.error(e.value_mark, e.path, message);
  return false;
}

}  // namespace fetouch::config::detail
