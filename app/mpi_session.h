// MPI (and PETSc, through deal.II) for the commands that solve: initialised when the first such
// command runs, finalised at exit. Open MPI 4 singletons share a session directory under /tmp,
// and two fetouch processes starting at once can break each other's MPI_Init; each process gets
// its own session directory base unless the caller chose one (OMPI_MCA_orte_tmpdir_base).
#pragma once

namespace fetouch::app {

void ensure_mpi();

}  // namespace fetouch::app
