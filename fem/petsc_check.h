// A PETSc error code turned into an exception that says what was being done, for the fem
// translation units that call PETSc directly (tangent_system*.cc, aggregation_multigrid.cc).
#pragma once

#include <petscsys.h>

#include <stdexcept>
#include <string>

namespace fetouch::fem {

inline void petsc_check(PetscErrorCode code, const char* what) {
  if (code != 0) throw std::runtime_error(std::string("PETSc error ") + std::to_string(code) + " in " + what);
}

}  // namespace fetouch::fem
