// Small helpers shared by the fem translation units that call PETSc directly (tangent_system*.cc,
// aggregation_multigrid.cc): a PETSc error code turned into an exception that says what was being
// done, and a stopwatch's reading.
#pragma once

#include <petscsys.h>

#include <chrono>
#include <stdexcept>
#include <string>

namespace fetouch::fem {

inline void petsc_check(PetscErrorCode code, const char* what) {
  if (code != 0) throw std::runtime_error(std::string("PETSc error ") + std::to_string(code) + " in " + what);
}

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace fetouch::fem
