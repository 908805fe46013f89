#include <gtest/gtest.h>

#include <sstream>

#include "app/log.h"
#include "app/progress.h"

namespace fetouch::app {
namespace {

TEST(Log, LevelsFilterMessages) {
  std::ostringstream sink;
  log::set_stream(&sink);
  log::set_level(log::Level::warning);
  log::error() << "bad " << 1;
  log::warning() << "careful";
  log::info() << "hidden";
  log::set_level(log::Level::debug);
  log::debug() << "shown";
  log::set_level(log::Level::info);
  log::set_stream(nullptr);
  EXPECT_EQ(sink.str(), "error: bad 1\nwarning: careful\ndebug: shown\n");
}

TEST(Progress, PlainLinesAtEveryTenthWhenNotATerminal) {
  std::ostringstream out;
  {
    Progress progress("meshing", 200, out, /*terminal=*/false);
    for (long i = 0; i <= 200; ++i) progress.update(i);
  }
  // 0 %, 10 %, ..., 100 %: eleven lines, no carriage returns.
  int lines = 0;
  for (char c : out.str()) lines += c == '\n';
  EXPECT_EQ(lines, 11);
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
  EXPECT_NE(out.str().find("meshing: 50% (100/200)"), std::string::npos);
  EXPECT_NE(out.str().find("meshing: 100% (200/200)"), std::string::npos);
}

TEST(Progress, RedrawsInPlaceOnATerminal) {
  std::ostringstream out;
  Progress progress("solving", 4, out, /*terminal=*/true);
  progress.update(2);
  progress.finish();
  const std::string text = out.str();
  EXPECT_NE(text.find("\rsolving  [##########..........]  50%"), std::string::npos) << text;
  EXPECT_NE(text.find("100%  4/4"), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
}

TEST(Progress, QuietMeansNoProgress) {
  std::ostringstream out;
  log::set_level(log::Level::error);
  {
    Progress progress("x", 10, out, false);
    progress.update(5);
  }
  log::set_level(log::Level::info);
  EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace fetouch::app
