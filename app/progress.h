// Progress of long work. On a terminal: one line redrawn in place,
//   meshing  [##########..........]  50%  120/240  eta 4 s
// elsewhere (a pipe, a CI log): a plain line at every tenth of the way, so logs stay readable.
#pragma once

#include <chrono>
#include <ostream>
#include <string>

namespace fetouch::app {

class Progress {
 public:
  // `terminal`: redraw in place; pass is_terminal(stream) unless a test wants otherwise.
  Progress(std::string label, long total, std::ostream& out, bool terminal);
  ~Progress();

  void update(long done);
  void finish();

  static bool stderr_is_terminal();

 private:
  void draw(long done);

  std::string label_;
  long total_;
  std::ostream& out_;
  bool terminal_;
  bool finished_ = false;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace fetouch::app
