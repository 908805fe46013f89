#include "app/log.h"

#include <iostream>
#include <mutex>

namespace fetouch::app::log {

namespace {
Level current_level = Level::info;
std::ostream* sink = &std::cerr;
std::mutex sink_mutex;  // several threads (solver, I/O) may log; lines must not interleave
}  // namespace

void set_level(Level l) { current_level = l; }
Level level() { return current_level; }
bool enabled(Level l) { return static_cast<int>(l) <= static_cast<int>(current_level); }
void set_stream(std::ostream* stream) { sink = stream ? stream : &std::cerr; }

Line::~Line() {
  if (!enabled_) return;
  const char* prefix = "";
  switch (level_) {
    case Level::error: prefix = "error: "; break;
    case Level::warning: prefix = "warning: "; break;
    case Level::debug: prefix = "debug: "; break;
    default: break;
  }
  std::lock_guard<std::mutex> lock(sink_mutex);
  *sink << prefix << text_.str() << '\n';
  sink->flush();
}

}  // namespace fetouch::app::log
