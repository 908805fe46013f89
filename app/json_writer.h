// A small streaming JSON writer for `--json` output. Writes compact, valid JSON (RFC 8259):
// strings escaped, non-finite numbers written as null.
//
//   JsonWriter json(std::cout);
//   json.begin_object(); json.key("cells").value(3072); json.end_object();
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace fetouch::app {

class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& out) : out_(out) {}

  JsonWriter& begin_object();
  JsonWriter& end_object();
  JsonWriter& begin_array();
  JsonWriter& end_array();
  JsonWriter& key(const std::string& name);
  JsonWriter& value(const std::string& text);
  JsonWriter& value(const char* text) { return value(std::string(text)); }
  JsonWriter& value(double number);
  JsonWriter& value(long number);
  JsonWriter& value(int number) { return value(static_cast<long>(number)); }
  JsonWriter& value(unsigned int number) { return value(static_cast<long>(number)); }
  JsonWriter& value(bool flag);
  JsonWriter& null();
  // An array of the range's values (numbers, strings, flags).
  template <class Range>
  JsonWriter& values(const Range& range) {
    begin_array();
    for (const auto& v : range) value(v);
    return end_array();
  }

  static std::string escape(const std::string& text);

 private:
  void separate();
  std::ostream& out_;
  std::vector<bool> first_;  // per open container: nothing written in it yet
  bool after_key_ = false;
};

}  // namespace fetouch::app
