// The JSON writer's output, parsed back by an independent parser (yaml-cpp reads JSON).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "app/json_writer.h"

namespace fetouch::app {
namespace {

TEST(JsonWriter, NestedValuesRoundTrip) {
  std::ostringstream out;
  JsonWriter json(out);
  json.begin_object();
  json.key("name").value("a \"quoted\"\nline\t\\");
  json.key("count").value(3);
  json.key("ratio").value(0.1);
  json.key("third").value(1.0 / 3.0);
  json.key("ok").value(true);
  json.key("bad").value(std::nan(""));
  json.key("list").begin_array().value(1).value("two").begin_object().end_object().end_array();
  json.end_object();

  const YAML::Node node = YAML::Load(out.str());
  EXPECT_EQ(node["name"].as<std::string>(), "a \"quoted\"\nline\t\\");
  EXPECT_EQ(node["count"].as<int>(), 3);
  EXPECT_EQ(node["ratio"].as<double>(), 0.1);          // shortest form that reads back exactly
  EXPECT_EQ(node["third"].as<double>(), 1.0 / 3.0);
  EXPECT_TRUE(node["ok"].as<bool>());
  EXPECT_TRUE(node["bad"].IsNull());                   // JSON has no NaN
  EXPECT_EQ(node["list"].size(), 3u);
  EXPECT_EQ(node["list"][1].as<std::string>(), "two");
  EXPECT_NE(out.str().find("\"ratio\":0.1,"), std::string::npos);
}

TEST(JsonWriter, EscapesControlCharacters) {
  EXPECT_EQ(JsonWriter::escape(std::string("a\x01") + "b"), "a\\u0001b");
}

}  // namespace
}  // namespace fetouch::app
