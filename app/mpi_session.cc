#include "app/mpi_session.h"

#include <mpi.h>

#include <memory>

#include "app/log.h"
#include "fem/mpi_session.h"

namespace fetouch::app {

void ensure_mpi() {
  static int argc = 1;
  static char name[] = "fetouch";
  static char* argv_storage[] = {name, nullptr};
  static char** argv = argv_storage;
  static const std::unique_ptr<fem::MpiSession> session = [] {
    auto started = std::make_unique<fem::MpiSession>(argc, argv);
    // Under mpirun every rank runs the same command: progress is said once, by rank 0; every rank
    // still says its warnings and errors.
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank != 0 && log::enabled(log::Level::info)) log::set_level(log::Level::warning);
    return started;
  }();
}

}  // namespace fetouch::app
