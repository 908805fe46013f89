#include "fem/mpi_session.h"

#include <deal.II/base/mpi.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <string>

namespace fetouch::fem {

namespace {

// The session directories of fetouch processes that ended without removing theirs (killed by a
// signal): fetouch_mpi_PID where no process PID is left. Best effort, quietly.
void remove_orphaned_directories(const std::filesystem::path& temporary) {
  std::error_code error;
  std::filesystem::directory_iterator entry(temporary, error), end;
  for (; !error && entry != end; entry.increment(error)) {
    const std::string name = entry->path().filename().string();
    const std::string prefix = "fetouch_mpi_";
    if (name.compare(0, prefix.size(), prefix) != 0 || name.size() == prefix.size()) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid <= 0 || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    std::filesystem::remove_all(entry->path(), ignored);
  }
}

}  // namespace

struct MpiSession::Mpi {
  dealii::Utilities::MPI::MPI_InitFinalize init;
  Mpi(int& argc, char**& argv) : init(argc, argv, 1) {}
};

MpiSession::MpiSession(int& argc, char**& argv) {
  // Only for singletons: under mpirun the launcher's session directory is the one to use.
  const bool launched = std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr || std::getenv("PMIX_RANK") != nullptr;
  if (!launched) {
    // A singleton has no peers: without these, Open MPI 4 starts an `orted` daemon (0.2 s) and
    // loads the InfiniBand/Omni-Path transports (0.1 s each) before the first line of work. The
    // caller's own settings win (setenv without overwrite).
    setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
    setenv("OMPI_MCA_pml", "ob1", 0);
  }
  if (!launched && !std::getenv("OMPI_MCA_orte_tmpdir_base")) {
    remove_orphaned_directories(std::filesystem::temp_directory_path());
    directory_ = std::filesystem::temp_directory_path() / ("fetouch_mpi_" + std::to_string(::getpid()));
    std::filesystem::create_directories(directory_);
    setenv("OMPI_MCA_orte_tmpdir_base", directory_.c_str(), 1);
  }
  mpi_ = std::make_unique<Mpi>(argc, argv);
}

MpiSession::~MpiSession() {
  mpi_.reset();  // MPI_Finalize before the directory goes
  std::error_code ignored;
  if (!directory_.empty()) std::filesystem::remove_all(directory_, ignored);
}

}  // namespace fetouch::fem
