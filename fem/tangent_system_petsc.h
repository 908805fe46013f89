// TangentSystem's PETSc objects, shared by its translation units (private to fem/tangent_system*.cc).
#pragma once

#include <petscksp.h>

#include "fem/tangent_system.h"

namespace fetouch::fem {

struct TangentSystem::Petsc {
  Mat mat = nullptr;
  KSP ksp = nullptr;
  PC pc = nullptr;
  Vec b = nullptr, x = nullptr;
  bool factored = false;
  void destroy() {
    if (ksp) KSPDestroy(&ksp);
    if (mat) MatDestroy(&mat);
    if (b) VecDestroy(&b);
    if (x) VecDestroy(&x);
    ksp = nullptr, mat = nullptr, b = nullptr, x = nullptr, pc = nullptr;
    factored = false;
  }
  ~Petsc() { destroy(); }
};

}  // namespace fetouch::fem
