// MPI (and PETSc) for the commands that solve: started when the first such command runs, finished
// at exit (fem/mpi_session.h says how concurrent fetouch processes are kept apart).
#pragma once

namespace fetouch::app {

void ensure_mpi();

}  // namespace fetouch::app
