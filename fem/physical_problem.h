// A valid scene whose physics cannot do what it asks: a tissue that nothing holds, one that falls
// apart into pieces nothing holds, one that cannot carry its own weight. Not bad input (the file is
// valid), but the work failing for a physical reason: the commands say so with exit code 1 and what
// to change, where std::runtime_error from the scene or mesh means exit code 2.
#pragma once

#include <stdexcept>
#include <string>

namespace fetouch::fem {

class PhysicalProblem : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace fetouch::fem
