// Seconds elapsed since a steady_clock reading: the phase timings the solver reports (fem/ only).
#pragma once

#include <chrono>

namespace fetouch::fem {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace fetouch::fem
