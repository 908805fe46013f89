// Line and point charts written to PNG with VTK's charts, offscreen: the plots of `fetouch
// stability` (regions, volumes, step responses). Debian's VTK draws only with an X display, even
// offscreen; without one it crashes, so callers check display_available() first and tell the user
// to run under `xvfb-run -a` instead.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace fetouch::app {

struct ChartSeries {
  std::string name;                     // the legend's entry
  std::vector<double> x, y;
  std::array<unsigned char, 3> color{0, 0, 0};
  bool points = false;                  // markers instead of a line
  float width = 2.0f;                   // line width or marker size, pixels
  bool bars = false;                    // bars (at x = 0, 1, 2, ...; Chart::x_ticks names them)
};

struct Chart {
  std::string title, x_label, y_label;
  std::vector<ChartSeries> series;
  int width = 1000, height = 700;
  bool log_x = false, log_y = false;    // logarithmic axes (every value must be positive)
  std::vector<std::string> x_ticks;     // bar charts: the label of bar 0, 1, 2, ...
};

// An X display to draw on ($DISPLAY set and not empty).
bool display_available();
// A display a window can open on (the trainer's and the review's Qt windows): X, or Wayland.
bool window_display_available();

// The sentence to print when it is not.
std::string no_display_hint(const std::filesystem::path& png);

// Draws the chart and writes it as PNG. Throws std::runtime_error if the file cannot be written
// or there is no display.
void write_chart_png(const Chart& chart, const std::filesystem::path& png);

}  // namespace fetouch::app
