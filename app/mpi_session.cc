#include "app/mpi_session.h"

#include <deal.II/base/mpi.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

namespace fetouch::app {

namespace {

struct Session {
  std::filesystem::path directory;
  std::unique_ptr<dealii::Utilities::MPI::MPI_InitFinalize> mpi;
  ~Session() {
    mpi.reset();
    std::error_code ignored;
    if (!directory.empty()) std::filesystem::remove_all(directory, ignored);
  }
};

}  // namespace

void ensure_mpi() {
  static Session session;
  if (session.mpi) return;
  if (!std::getenv("OMPI_MCA_orte_tmpdir_base")) {
    session.directory = std::filesystem::temp_directory_path() / ("fetouch_mpi_" + std::to_string(::getpid()));
    std::filesystem::create_directories(session.directory);
    setenv("OMPI_MCA_orte_tmpdir_base", session.directory.c_str(), 1);
  }
  static int argc = 1;
  static char name[] = "fetouch";
  static char* argv_storage[] = {name, nullptr};
  static char** argv = argv_storage;
  session.mpi = std::make_unique<dealii::Utilities::MPI::MPI_InitFinalize>(argc, argv, 1);
}

}  // namespace fetouch::app
