// GoogleTest main for suites that use PETSc or MPI through deal.II: MPI (and PETSc) are initialised
// once for the process, before any test, and finalised after all of them.
#include <deal.II/base/mpi.h>
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
