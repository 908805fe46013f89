#include "app/mpi_session.h"

#include <memory>

#include "fem/mpi_session.h"

namespace fetouch::app {

void ensure_mpi() {
  static int argc = 1;
  static char name[] = "fetouch";
  static char* argv_storage[] = {name, nullptr};
  static char** argv = argv_storage;
  static const std::unique_ptr<fem::MpiSession> session = std::make_unique<fem::MpiSession>(argc, argv);
}

}  // namespace fetouch::app
