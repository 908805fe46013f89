// GoogleTest main for suites that use PETSc or MPI through deal.II: MPI (and PETSc) are initialised
// once for the process, before any test, and finalised after all of them.
//
// ctest starts one process per test, several at a time. Open MPI 4's singleton start-up shares a
// session directory under /tmp between processes, and one process cleaning it up while another
// creates it fails MPI_Init ("orte_session_dir failed"); each process therefore gets its own
// session directory base, unless the caller chose one.
#include <deal.II/base/mpi.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

int main(int argc, char** argv) {
  const std::filesystem::path session =
      std::filesystem::temp_directory_path() / ("fetouch_mpi_" + std::to_string(::getpid()));
  std::filesystem::create_directories(session);
  setenv("OMPI_MCA_orte_tmpdir_base", session.c_str(), /*overwrite=*/0);
  int result;
  {
    dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
    ::testing::InitGoogleTest(&argc, argv);
    result = RUN_ALL_TESTS();
  }
  std::error_code ignored;
  std::filesystem::remove_all(session, ignored);
  return result;
}
