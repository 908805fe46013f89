// Smoothed-aggregation multigrid of our own, handed to PETSc's PCMG (issue 40).
//
// PETSc 3.18's GAMG coarsens some of our meshes badly: its heavy-edge matching leaves about three
// nodes an aggregate on a block cut into tetrahedra, single nodes among them whose six coarse
// columns are half zero, and the levels stall until a set-up fails (docs/benchmarks.md, "Why GAMG
// coarsens this block badly"). Here a node's aggregate is the node and all its neighbours, as in
// Vaněk, Mandel and Brezina's smoothed aggregation (Computing 56, 1996): phase 1 takes, in order,
// every node whose neighbours are all free as a root with its neighbourhood; phase 2 gives each
// node left over to the aggregate it is most strongly coupled to. An aggregate too small to carry
// the near-null space (fewer than three nodes of three dofs for the six rigid-body modes) joins a
// neighbouring one. The same matrix always gives the same aggregates.
//
// Each aggregate's rows of the near-null space B are split B = Q R (thin QR): Q is its block of the
// prolongator, R its rows of the coarse level's near-null space, and the coarse operator is P^T A P.
// Plain aggregation by default: P is Q itself. Smoothing it once by damped Jacobi (smoothed
// aggregation, P = (I - w D^-1 A) Q, w = 4 / (3 rho(D^-1 A)); `smoothings = 1`) cut CG's iterations
// by a third but doubled the time of a 45,441-DOF press (6.05 s against 3.25 s) and, at 334,620
// DOFs, made the first coarse level 45,102 rows of 352 entries each and the set-up 4 GB
// (docs/benchmarks.md). Under MPI each rank aggregates the nodes of its own rows (couplings to other
// ranks' rows are not edges), so no aggregate spans two ranks. Levels are added until the coarsest
// has at most `coarse_rows` rows (it is factorised: PCMG's LU on one rank, redundant LU on several)
// or a level would keep more than 80 % of its rows.
#pragma once

#include <petscksp.h>

#include <cstddef>
#include <vector>

#include "fem/multigrid_level.h"

namespace fetouch::fem {

struct AggregationSettings {
  int node_block = 3;        // rows of a node on the fine level (they are consecutive)
  double strength = 0.0;     // a coupling is an edge when |A_ij| > strength * sqrt(|A_ii| |A_jj|) (Frobenius)
  int smoothings = 0;        // prolongator smoothings: 0, plain aggregation (below)
  int coarse_rows = 1000;    // stop coarsening at or below this many rows
  int max_levels = 10;
  int smoother_steps = 2;    // Chebyshev/Jacobi steps before and after the coarse correction (W-cycles)
};

// Builds the hierarchy of A (square, MPIAIJ or SEQAIJ, rows node by node) into pc, which becomes a
// PCMG with Chebyshev/Jacobi smoothers; its levels read PETSC_OPTIONS (-mg_levels_*, -mg_coarse_*).
// `null_space` holds `vectors` vectors of A's local rows, vector v at [v * local_rows + i], and
// should be orthonormal. Returns the levels, finest first. Collective on A's communicator; throws
// std::runtime_error when PETSc fails.
std::vector<MultigridLevel> build_aggregation_multigrid(PC pc, Mat A, const double* null_space, int vectors,
                                                        const AggregationSettings& settings);

// The aggregates of a node graph (local, CSR over nodes; `weight` the strength of each edge, self
// loops ignored): aggregate[i] is node i's aggregate, -1 for a node left out (one with no edges:
// held nodes, whose rows are their diagonals alone). `min_size` is the fewest nodes an aggregate may
// have where a neighbour can take it in. Exposed for tests.
std::vector<int> aggregate_nodes(const std::vector<int>& row_start, const std::vector<int>& columns,
                                 const std::vector<double>& weight, int min_size, int* count);

}  // namespace fetouch::fem
