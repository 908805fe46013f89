// MPI (and PETSc, through deal.II) for the lifetime of one object: what the solver needs before it
// builds a PETSc matrix. Open MPI 4 singletons share a session directory under /tmp, and two
// processes starting at once (ctest -j, several fetouch commands) can break each other's MPI_Init
// ("orte_session_dir failed"); each session therefore gets its own directory base, removed at the
// end, unless the caller chose one (OMPI_MCA_orte_tmpdir_base); those that killed processes left
// behind are removed when the next session starts. A singleton also runs without the
// `orted` daemon and the fabric transports, which cost half a second of start-up and serve no peer.
#pragma once

#include <filesystem>
#include <memory>

namespace fetouch::fem {

class MpiSession {
 public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

 private:
  struct Mpi;
  std::filesystem::path directory_;
  std::unique_ptr<Mpi> mpi_;
};

}  // namespace fetouch::fem
