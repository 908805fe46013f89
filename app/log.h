// The one logging facility of the command line: leveled messages on stderr, so that stdout carries
// only results (summaries, JSON). `-q` keeps errors only, `-v` adds detail, `-vv` debugging.
//
//   log::info() << "meshed " << cells << " cells";
//
// Not for the haptic tick: a message is formatted and written while the statement runs.
#pragma once

#include <ostream>
#include <sstream>

namespace fetouch::app::log {

enum class Level { error = 0, warning = 1, info = 2, detail = 3, debug = 4 };

void set_level(Level level);
Level level();
bool enabled(Level level);
// Where messages go (stderr unless a test redirects them).
void set_stream(std::ostream* stream);

// Collects one message and writes it, prefixed by its level, when it goes out of scope.
class Line {
 public:
  explicit Line(Level level) : level_(level), enabled_(enabled(level)) {}
  ~Line();
  Line(const Line&) = delete;
  Line& operator=(const Line&) = delete;

  template <class T>
  Line& operator<<(const T& value) {
    if (enabled_) text_ << value;
    return *this;
  }

 private:
  Level level_;
  bool enabled_;
  std::ostringstream text_;
};

inline Line error() { return Line(Level::error); }
inline Line warning() { return Line(Level::warning); }
inline Line info() { return Line(Level::info); }
inline Line detail() { return Line(Level::detail); }
inline Line debug() { return Line(Level::debug); }

}  // namespace fetouch::app::log
