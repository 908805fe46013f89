#include "fem/aggregation_multigrid.h"

#include <Eigen/Dense>

#include "fem/petsc_check.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace fetouch::fem {
namespace {

// A level's node graph from its local rows (columns of other ranks' rows are left out).
struct NodeGraph {
  std::vector<int> row_start{0}, columns;
  std::vector<double> weight;
};

// The rows' couplings among this rank's own rows: the diagonal block of an MPIAIJ matrix, or the
// whole of a SEQAIJ one, read as CSR arrays (no copy).
struct LocalRows {
  Mat block = nullptr;
  PetscInt rows = 0;
  const PetscInt *start = nullptr, *columns = nullptr;
  const PetscScalar* values = nullptr;
  explicit LocalRows(Mat a) {
    PetscBool mpi = PETSC_FALSE;
    petsc_check(PetscObjectTypeCompare(reinterpret_cast<PetscObject>(a), MATMPIAIJ, &mpi), "reading the matrix type");
    block = a;
    if (mpi) petsc_check(MatMPIAIJGetSeqAIJ(a, &block, nullptr, nullptr), "reading the rank's rows");
    PetscBool done = PETSC_FALSE;
    petsc_check(MatGetRowIJ(block, 0, PETSC_FALSE, PETSC_FALSE, &rows, &start, &columns, &done), "reading the rank's rows");
    if (!done) throw std::runtime_error("multigrid set-up: the matrix gives no row arrays");
    petsc_check(MatSeqAIJGetArrayRead(block, &values), "reading the rank's rows");
  }
  ~LocalRows() {
    PetscBool done = PETSC_FALSE;
    MatSeqAIJRestoreArrayRead(block, &values);
    MatRestoreRowIJ(block, 0, PETSC_FALSE, PETSC_FALSE, &rows, &start, &columns, &done);
  }
  LocalRows(const LocalRows&) = delete;
  LocalRows& operator=(const LocalRows&) = delete;
};

NodeGraph node_graph(Mat a, int block, double strength) {
  const LocalRows local(a);
  if (local.rows % block != 0) throw std::runtime_error("multigrid set-up: a rank's rows are not whole nodes");
  const int nodes = static_cast<int>(local.rows) / block;
  // Frobenius norms of the node-by-node blocks, one node row at a time, kept as a CSR of nodes.
  std::vector<double> sum(nodes, 0.0), diagonal(nodes, 0.0);
  std::vector<int> seen(nodes, -1), touched, start{0}, neighbour;
  std::vector<double> norm;
  for (int i = 0; i < nodes; ++i) {
    touched.clear();
    for (int d = 0; d < block; ++d) {
      const PetscInt row = i * block + d;
      for (PetscInt e = local.start[row]; e < local.start[row + 1]; ++e) {
        const int j = static_cast<int>(local.columns[e]) / block;
        if (seen[j] != i) seen[j] = i, sum[j] = 0, touched.push_back(j);
        sum[j] += local.values[e] * local.values[e];
      }
    }
    std::sort(touched.begin(), touched.end());
    for (const int j : touched) {
      if (j == i) diagonal[i] = std::sqrt(sum[j]);
      else if (sum[j] > 0) neighbour.push_back(j), norm.push_back(std::sqrt(sum[j]));
    }
    start.push_back(static_cast<int>(neighbour.size()));
  }
  NodeGraph g;
  for (int i = 0; i < nodes; ++i) {
    for (int e = start[i]; e < start[i + 1]; ++e)
      if (norm[e] > strength * std::sqrt(diagonal[i] * diagonal[neighbour[e]]))
        g.columns.push_back(neighbour[e]), g.weight.push_back(norm[e]);
    g.row_start.push_back(static_cast<int>(g.columns.size()));
  }
  return g;
}

struct Coarsened {
  Mat p = nullptr;                  // prolongator, coarse to fine
  std::vector<double> null_space;   // of the coarse level's local rows
  int local_coarse = 0;
  std::size_t aggregates = 0, aggregated_nodes = 0;  // this rank's
};

// The tentative prolongator of the aggregates and the coarse near-null space (thin QR per aggregate).
Coarsened tentative(Mat a, int block, const std::vector<int>& aggregate, int count, const double* null_space,
                    int vectors) {
  MPI_Comm comm = PetscObjectComm(reinterpret_cast<PetscObject>(a));
  PetscInt begin = 0, end = 0;
  petsc_check(MatGetOwnershipRange(a, &begin, &end), "reading the rows");
  const int local = static_cast<int>(end - begin);
  Coarsened c;
  c.local_coarse = count * vectors;
  long long offset = 0, mine = c.local_coarse;
  MPI_Exscan(&mine, &offset, 1, MPI_LONG_LONG, MPI_SUM, comm);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  if (rank == 0) offset = 0;

  // Each aggregate's nodes, in node order: members[first[g], first[g + 1]) (a counting sort).
  std::vector<int> first(count + 1, 0), members;
  for (const int g : aggregate)
    if (g >= 0) ++first[g + 1];
  for (int g = 0; g < count; ++g) first[g + 1] += first[g];
  members.resize(first[count]);
  {
    std::vector<int> next(first.begin(), first.end() - 1);
    for (int i = 0; i < static_cast<int>(aggregate.size()); ++i)
      if (aggregate[i] >= 0) members[next[aggregate[i]]++] = i;
  }
  c.aggregated_nodes = members.size();
  c.aggregates = static_cast<std::size_t>(count);

  petsc_check(MatCreate(comm, &c.p), "creating a prolongator");
  try {  // the prolongator released if filling it fails
    petsc_check(MatSetSizes(c.p, local, c.local_coarse, PETSC_DETERMINE, PETSC_DETERMINE), "sizing a prolongator");
    petsc_check(MatSetBlockSizes(c.p, block, vectors), "sizing a prolongator");
    petsc_check(MatSetType(c.p, MATAIJ), "creating a prolongator");
    petsc_check(MatSeqAIJSetPreallocation(c.p, vectors, nullptr), "allocating a prolongator");
    petsc_check(MatMPIAIJSetPreallocation(c.p, vectors, nullptr, 0, nullptr), "allocating a prolongator");
    c.null_space.assign(static_cast<std::size_t>(c.local_coarse) * vectors, 0.0);
    std::vector<PetscInt> cols(vectors);
    std::vector<PetscScalar> values(vectors);
    for (int g = 0; g < count; ++g) {
      const int* nodes = members.data() + first[g];
      const int size = first[g + 1] - first[g];
      const int rows = size * block;
      Eigen::MatrixXd b(rows, vectors);
      for (int m = 0; m < size; ++m)
        for (int d = 0; d < block; ++d)
          for (int v = 0; v < vectors; ++v) b(m * block + d, v) = null_space[std::size_t(v) * local + nodes[m] * block + d];
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(b);
      Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(rows, vectors);
      Eigen::MatrixXd r = qr.matrixQR().topRows(vectors).triangularView<Eigen::Upper>();
      for (int v = 0; v < vectors; ++v)
        if (r(v, v) < 0) q.col(v) *= -1, r.row(v) *= -1;
      for (int v = 0; v < vectors; ++v) cols[v] = static_cast<PetscInt>(offset + g * vectors + v);
      for (int m = 0; m < size; ++m)
        for (int d = 0; d < block; ++d) {
          const PetscInt row = begin + nodes[m] * block + d;
          for (int v = 0; v < vectors; ++v) values[v] = q(m * block + d, v);
          petsc_check(MatSetValues(c.p, 1, &row, vectors, cols.data(), values.data(), INSERT_VALUES), "filling a prolongator");
        }
      for (int v = 0; v < vectors; ++v)
        for (int w = 0; w < vectors; ++w) c.null_space[std::size_t(v) * c.local_coarse + g * vectors + w] = r(w, v);
    }
    petsc_check(MatAssemblyBegin(c.p, MAT_FINAL_ASSEMBLY), "assembling a prolongator");
    petsc_check(MatAssemblyEnd(c.p, MAT_FINAL_ASSEMBLY), "assembling a prolongator");
  } catch (...) {
    MatDestroy(&c.p);
    throw;
  }
  return c;
}

// rho(D^-1 A) by power iteration, from a start that depends on global row numbers only.
double jacobi_spectral_radius(Mat a, Vec inverse_diagonal) {
  Vec x = nullptr, y = nullptr;
  petsc_check(MatCreateVecs(a, &x, &y), "creating vectors");
  PetscInt begin = 0, end = 0;
  petsc_check(VecGetOwnershipRange(x, &begin, &end), "reading the rows");
  double* values = nullptr;
  petsc_check(VecGetArray(x, &values), "filling a vector");
  for (PetscInt i = begin; i < end; ++i) {
    const std::uint64_t h = (static_cast<std::uint64_t>(i) + 1) * 0x9E3779B97F4A7C15ull;
    values[i - begin] = 0.5 + static_cast<double>((h >> 11) & 0xFFFFF) / double(0xFFFFF);
  }
  petsc_check(VecRestoreArray(x, &values), "filling a vector");
  double rho = 0, norm = 0;
  petsc_check(VecNorm(x, NORM_2, &norm), "a norm");
  petsc_check(VecScale(x, 1.0 / norm), "scaling");
  for (int k = 0; k < 20; ++k) {
    petsc_check(MatMult(a, x, y), "a product");
    petsc_check(VecPointwiseMult(y, y, inverse_diagonal), "scaling");
    petsc_check(VecNorm(y, NORM_2, &rho), "a norm");
    if (!(rho > 0)) break;
    petsc_check(VecScale(y, 1.0 / rho), "scaling");
    std::swap(x, y);
  }
  VecDestroy(&x);
  VecDestroy(&y);
  return rho;
}

// P = (I - w D^-1 A) P0, w = 4 / (3 rho). Replaces p.
void smooth(Mat a, Mat& p) {
  Vec d = nullptr;
  petsc_check(MatCreateVecs(a, nullptr, &d), "creating a vector");
  petsc_check(MatGetDiagonal(a, d), "reading the diagonal");
  petsc_check(VecReciprocal(d), "inverting the diagonal");
  const double rho = jacobi_spectral_radius(a, d);
  const double w = rho > 0 ? 4.0 / (3.0 * 1.05 * rho) : 0.0;
  Mat ap = nullptr;
  petsc_check(MatMatMult(a, p, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &ap), "smoothing a prolongator");
  petsc_check(MatDiagonalScale(ap, d, nullptr), "smoothing a prolongator");
  petsc_check(MatAYPX(ap, -w, p, SUBSET_NONZERO_PATTERN), "smoothing a prolongator");
  VecDestroy(&d);
  MatDestroy(&p);
  p = ap;
}

MultigridLevel describe(Mat a) {
  PetscInt rows = 0;
  MatInfo info;
  petsc_check(MatGetSize(a, &rows, nullptr), "reading a level");
  petsc_check(MatGetInfo(a, MAT_GLOBAL_SUM, &info), "reading a level");
  MultigridLevel level;
  level.rows = static_cast<std::size_t>(rows);
  level.nonzeros = static_cast<std::size_t>(info.nz_used);
  return level;
}

}  // namespace

std::vector<int> aggregate_nodes(const std::vector<int>& row_start, const std::vector<int>& columns,
                                 const std::vector<double>& weight, int min_size, int* count) {
  const int nodes = static_cast<int>(row_start.size()) - 1;
  constexpr int free = -1, left_out = -2;
  std::vector<int> aggregate(nodes, free);
  auto edges = [&](int i) { return row_start[i + 1] - row_start[i]; };
  int next = 0;
  // Phase 1: roots whose neighbourhoods are wholly free.
  for (int i = 0; i < nodes; ++i) {
    if (edges(i) == 0) {
      aggregate[i] = left_out;
      continue;
    }
    if (aggregate[i] != free) continue;
    bool all_free = true;
    for (int e = row_start[i]; e < row_start[i + 1] && all_free; ++e) all_free = aggregate[columns[e]] == free;
    if (!all_free) continue;
    aggregate[i] = next;
    for (int e = row_start[i]; e < row_start[i + 1]; ++e) aggregate[columns[e]] = next;
    ++next;
  }
  // Phase 2: the rest join the aggregate they are most strongly coupled to (phase 1's aggregates).
  const std::vector<int> first = aggregate;
  for (int i = 0; i < nodes; ++i) {
    if (first[i] != free) continue;
    int best = free;
    double strongest = -1;
    for (int e = row_start[i]; e < row_start[i + 1]; ++e)
      if (first[columns[e]] >= 0 && weight[e] > strongest) strongest = weight[e], best = first[columns[e]];
    // Every free node has a neighbour in phase 1's aggregates, else it would have been a root (its
    // neighbours are never left out: a left-out node has no edges, and the graph is symmetric).
    // Its own aggregate otherwise, which the size check below merges or leaves out.
    aggregate[i] = best >= 0 ? best : next++;
  }
  // Aggregates too small for the near-null space join their most strongly coupled neighbour.
  std::vector<int> size(next, 0), target(next);
  for (int i = 0; i < nodes; ++i)
    if (aggregate[i] >= 0) ++size[aggregate[i]];
  for (int g = 0; g < next; ++g) target[g] = g;
  std::vector<double> strongest(next, -1);
  for (int i = 0; i < nodes; ++i) {
    const int g = aggregate[i];
    if (g < 0 || size[g] >= min_size) continue;
    for (int e = row_start[i]; e < row_start[i + 1]; ++e) {
      const int h = aggregate[columns[e]];
      if (h >= 0 && h != g && size[h] >= min_size && weight[e] > strongest[g]) strongest[g] = weight[e], target[g] = h;
    }
  }
  std::vector<int> number(next, -1);
  int kept = 0;
  for (int g = 0; g < next; ++g)
    if (target[g] == g && size[g] >= min_size) number[g] = kept++;
  for (int i = 0; i < nodes; ++i) {
    if (aggregate[i] < 0) {
      aggregate[i] = -1;
      continue;
    }
    // A small aggregate with no neighbour to join (a rank's island) is left out.
    aggregate[i] = number[target[aggregate[i]]];
  }
  *count = kept;
  return aggregate;
}

std::vector<MultigridLevel> build_aggregation_multigrid(PC pc, Mat a, const double* null_space, int vectors,
                                                        const AggregationSettings& settings) {
  MPI_Comm comm = PetscObjectComm(reinterpret_cast<PetscObject>(a));
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  PetscInt begin = 0, end = 0;
  petsc_check(MatGetOwnershipRange(a, &begin, &end), "reading the rows");
  int block = settings.node_block;
  std::vector<double> constants;
  if (vectors == 0) {  // a node's components, each constant
    const int local = static_cast<int>(end - begin);
    vectors = block;
    constants.assign(std::size_t(local) * vectors, 0.0);
    for (int i = 0; i < local; ++i) constants[std::size_t(i % block) * local + i] = 1.0;
    null_space = constants.data();
  }
  // The coarse operators and prolongators made here, released however this returns (PCMG takes
  // its own references to those it is given).
  struct Made {
    std::vector<Mat> operators, prolongators;
    ~Made() {
      for (Mat& m : operators) MatDestroy(&m);
      for (Mat& m : prolongators) MatDestroy(&m);
    }
  } made;
  std::vector<Mat>& prolongators = made.prolongators;
  std::vector<Mat> operators{a};
  std::vector<MultigridLevel> levels{describe(a)};
  std::vector<double> coarse_null;
  const double* b = null_space;
  while (static_cast<int>(levels.size()) < settings.max_levels &&
         levels.back().rows > static_cast<std::size_t>(settings.coarse_rows)) {
    Mat fine = operators.back();
    const NodeGraph graph = node_graph(fine, block, settings.strength);
    const int min_size = block >= vectors ? 1 : vectors / block + 1;
    int count = 0;
    const std::vector<int> aggregate = aggregate_nodes(graph.row_start, graph.columns, graph.weight, min_size, &count);
    Coarsened c = tentative(fine, block, aggregate, count, b, vectors);
    unsigned long long mine[2] = {c.aggregates, c.aggregated_nodes}, all[2] = {0, 0};
    MPI_Allreduce(mine, all, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
    if (all[0] == 0 || all[0] * static_cast<unsigned long long>(vectors) >= 0.8 * levels.back().rows) {
      MatDestroy(&c.p);  // no coarsening worth a level
      break;
    }
    levels.back().aggregates = all[0];
    levels.back().nodes_per_aggregate = static_cast<double>(all[1]) / static_cast<double>(all[0]);
    prolongators.push_back(c.p);
    Mat& p = prolongators.back();
    for (int k = 0; k < settings.smoothings; ++k) smooth(fine, p);
    Mat coarse = nullptr;
    petsc_check(MatPtAP(fine, p, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &coarse), "forming a coarse level");
    made.operators.push_back(coarse);
    operators.push_back(coarse);
    levels.push_back(describe(coarse));
    coarse_null = std::move(c.null_space);
    b = coarse_null.data();
    block = vectors;
  }

  const int count = static_cast<int>(operators.size());
  petsc_check(PCSetType(pc, PCMG), "choosing multigrid");
  petsc_check(PCMGSetLevels(pc, count, nullptr), "setting the levels");
  petsc_check(PCMGSetType(pc, PC_MG_MULTIPLICATIVE), "choosing multiplicative cycles");
  // W-cycles: a V-cycle of plain aggregation loses with each level (CG's iterations a column 52 ->
  // 99 from 17,442 to 421,668 DOFs, 1.91x); a W-cycle visits the coarse levels twice and held them
  // to 42 -> 62 (1.46x), a column 11-13 % cheaper from 191,880 DOFs up, 29 % dearer at 17,442
  // (docs/benchmarks.md). PETSC_OPTIONS=-pc_mg_cycle_type v overrides.
  PetscBool cycle_given = PETSC_FALSE;
  petsc_check(PetscOptionsHasName(nullptr, nullptr, "-pc_mg_cycle_type", &cycle_given), "reading options");
  if (!cycle_given) petsc_check(PCMGSetCycleType(pc, PC_MG_CYCLE_W), "choosing W-cycles");
  petsc_check(PCMGSetGalerkin(pc, PC_MG_GALERKIN_NONE), "giving the coarse operators");
  for (int k = 0; k < count; ++k) {
    const int level = count - 1 - k;  // PCMG numbers the coarsest 0
    if (level > 0) {
      // Restriction P' set too: PCMG keeps the one it took from an earlier set-up's P otherwise.
      petsc_check(PCMGSetInterpolation(pc, level, prolongators[k]), "setting a prolongator");
      petsc_check(PCMGSetRestriction(pc, level, prolongators[k]), "setting a restriction");
      KSP smoother = nullptr;
      PC jacobi = nullptr;
      petsc_check(PCMGGetSmoother(pc, level, &smoother), "getting a smoother");
      petsc_check(KSPSetOperators(smoother, operators[k], operators[k]), "setting a level");
      petsc_check(KSPSetType(smoother, KSPCHEBYSHEV), "choosing Chebyshev");
      petsc_check(KSPChebyshevEstEigSet(smoother, 0, 0.1, 0, 1.1), "estimating eigenvalues");
      petsc_check(KSPSetTolerances(smoother, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, settings.smoother_steps), "smoothing");
      petsc_check(KSPGetPC(smoother, &jacobi), "getting a smoother");
      petsc_check(PCSetType(jacobi, PCJACOBI), "choosing Jacobi");
      petsc_check(KSPSetFromOptions(smoother), "reading PETSC_OPTIONS");
    } else {
      KSP coarse = nullptr;
      PC lu = nullptr;
      petsc_check(PCMGGetCoarseSolve(pc, &coarse), "getting the coarse solve");
      petsc_check(KSPSetOperators(coarse, operators[k], operators[k]), "setting the coarse level");
      petsc_check(KSPSetType(coarse, KSPPREONLY), "choosing the coarse solve");
      petsc_check(KSPGetPC(coarse, &lu), "getting the coarse solve");
      petsc_check(PCSetType(lu, ranks == 1 ? PCLU : PCREDUNDANT), "choosing the coarse factorisation");
      petsc_check(KSPSetFromOptions(coarse), "reading PETSC_OPTIONS");
    }
  }
  return levels;
}

}  // namespace fetouch::fem
