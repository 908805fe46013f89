// GoogleTest main for suites that use PETSc or MPI through deal.II: MPI (and PETSc) are initialised
// once for the process, before any test, and finalised after all of them. ctest runs these
// processes in parallel; fem::MpiSession keeps their Open MPI session directories apart.
#include <gtest/gtest.h>

#include "fem/mpi_session.h"

int main(int argc, char** argv) {
  fetouch::fem::MpiSession mpi(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
