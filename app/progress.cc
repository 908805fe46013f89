#include "app/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iomanip>

#include "app/log.h"

namespace fetouch::app {

Progress::Progress(std::string label, long total, std::ostream& out, bool terminal)
    : label_(std::move(label)), total_(std::max(1L, total)), out_(out), terminal_(terminal),
      start_(std::chrono::steady_clock::now()), last_draw_(start_ - std::chrono::seconds(1)) {}

Progress::~Progress() { finish(); }

bool Progress::stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

void Progress::update(long done) {
  if (finished_ || !log::enabled(log::Level::info)) return;
  done = std::clamp(done, 0L, total_);
  if (terminal_) {
    // Redrawing costs a write: at most 10 per second.
    const auto now = std::chrono::steady_clock::now();
    if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    draw(done);
  } else {
    const int decile = static_cast<int>(10 * done / total_);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    out_ << label_ << ": " << 10 * decile << "% (" << done << "/" << total_ << ")\n";
    out_.flush();
  }
}

void Progress::draw(long done) {
  const double fraction = double(done) / double(total_);
  const int width = 20, filled = static_cast<int>(fraction * width + 0.5);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  out_ << '\r' << label_ << "  [" << std::string(filled, '#') << std::string(width - filled, '.')
       << "] " << std::setw(3) << static_cast<int>(100 * fraction) << "%  " << done << "/" << total_;
  if (done > 0 && done < total_)
    out_ << "  eta " << std::fixed << std::setprecision(0) << elapsed * (1 - fraction) / fraction
         << " s" << std::defaultfloat;
  out_ << "\033[K";  // clear what a longer previous line left
  out_.flush();
}

void Progress::finish() {
  if (finished_) return;
  update(total_);
  finished_ = true;
  if (terminal_ && log::enabled(log::Level::info)) {
    out_ << '\n';
    out_.flush();
  }
}

}  // namespace fetouch::app
