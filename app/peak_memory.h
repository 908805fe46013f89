// How much memory a process has held at most: its peak resident set (the kernel's high-water mark,
// getrusage's ru_maxrss), which is what a machine must have for the run. Under mpirun each rank is
// a process of its own; `fetouch solve` reports every rank's (docs/solver.md, "`fetouch solve`").
#pragma once

#include <vector>

namespace fetouch::app {

// This process's peak resident memory so far, in MB (2^20 bytes); 0 where the system does not say.
double peak_resident_mb();

// Every rank's peak_resident_mb() on rank 0 of MPI_COMM_WORLD, in rank order (collective: every rank
// calls it; the other ranks get an empty list). One process without MPI: its own.
std::vector<double> peak_resident_mb_per_rank();

}  // namespace fetouch::app
