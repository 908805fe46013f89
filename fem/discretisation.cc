#include "fem/discretisation.h"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

namespace fetouch::fem {

using namespace dealii;

Discretisation::Discretisation(const Triangulation<3>& t, int degree, MPI_Comm c) : tria(t), dof(t), comm(c) {
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  if (degree < 1 || degree > 2) throw std::invalid_argument("element degree must be 1 or 2");
  simplex = tria.all_reference_cells_are_simplex();
  if (simplex) {
    fe = std::make_unique<FESystem<3>>(FE_SimplexP<3>(degree), 3);
    mapping = std::make_unique<MappingFE<3>>(FE_SimplexP<3>(1));
    // P1: one point (gradients are constant per cell). P2: the rule of order 3; the four-point
    // rule, though exact for the linear stiffness of affine cells, let a probe pushed 20 mm into a
    // soft block fail at 70 % of its load (spurious modes at large strain; tests/fem/test_hard_cases.cc).
    quadrature = std::make_unique<QGaussSimplex<3>>(degree == 1 ? 1 : 3);
    face_quadrature = std::make_unique<QGaussSimplex<2>>(degree + 1);
  } else if (tria.all_reference_cells_are_hyper_cube()) {
    fe = std::make_unique<FESystem<3>>(FE_Q<3>(degree), 3);
    mapping = std::make_unique<MappingQ<3>>(1);
    quadrature = std::make_unique<QGauss<3>>(degree + 1);
    face_quadrature = std::make_unique<QGauss<2>>(degree + 1);
  } else {
    throw std::invalid_argument("mixed tetrahedral and hexahedral meshes are not supported");
  }
  dof.distribute_dofs(*fe);
  partition();
  for (const auto& cell : dof.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      const auto face = cell->face(f);
      if (!face->at_boundary()) continue;
      BoundaryFace b;
      b.cell = cell, b.face = f, b.center = face->center(), b.diameter = face->diameter();
      b.vertices = face->n_vertices();
      for (unsigned int k = 0; k < b.vertices; ++k) {
        b.vertex[k] = face->vertex(k);
        for (unsigned int i = 0; i < 3; ++i) b.vertex_dof[3 * k + i] = face->vertex_dof_index(k, i);
      }
      boundary_faces_.push_back(b);
    }
}

// METIS splits the cells (computed on rank 0, broadcast: every rank must agree), and dofs are
// renumbered rank by rank. A dof whose cells are all one rank's is that rank's; a dof on the
// interface between ranks goes to whichever of its cells' ranks owns fewest dofs so far (the
// interfaces taken in dof order, a point's components together, so that every rank decides the
// same). The lowest of its cells' ranks, the rule before, gave rank 0 of 2 on the default scene
// 8.8 % more rows than the mean (4,101 against 3,438).
void Discretisation::partition() {
  const unsigned int cells = tria.n_active_cells();
  std::vector<unsigned int> part(cells, 0);
  if (ranks > 1) {
    if (rank == 0) {
      DynamicSparsityPattern connectivity;
      GridTools::get_face_connectivity_of_cells(tria, connectivity);
      SparsityPattern graph;
      graph.copy_from(connectivity);
      SparsityTools::partition(graph, static_cast<unsigned int>(ranks), part, SparsityTools::Partitioner::metis);
    }
    MPI_Bcast(part.data(), static_cast<int>(cells), MPI_UNSIGNED, 0, comm);
    const types::global_dof_index n = dof.n_dofs();
    const unsigned int none = static_cast<unsigned int>(ranks);
    // Each dof's ranks (a bit each, up to 64 ranks; more ranks fall back to the lowest rank) and
    // its point's first dof (the dof of component 0 with the same scalar base function in a cell).
    const bool bits = ranks <= 64;
    std::vector<std::uint64_t> touched(n, 0);
    std::vector<unsigned int> owner(n, none);
    std::vector<types::global_dof_index> leader(n);
    std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
    unsigned int k = 0;
    for (const auto& cell : dof.active_cell_iterators()) {
      cell->get_dof_indices(indices);
      for (unsigned int i = 0; i < indices.size(); ++i) {
        const types::global_dof_index g = indices[i];
        owner[g] = std::min(owner[g], part[k]);
        if (bits) touched[g] |= std::uint64_t(1) << part[k];
        const unsigned int base = fe->system_to_component_index(i).second;
        leader[g] = indices[fe->component_to_system_index(0, base)];
      }
      ++k;
    }
    if (bits) {  // counted in points (leaders), each point's components following its leader
      const auto shared = [&](types::global_dof_index i) { return (touched[i] & (touched[i] - 1)) != 0; };
      std::vector<types::global_dof_index> count(ranks, 0);
      for (types::global_dof_index i = 0; i < n; ++i)
        if (leader[i] == i && !shared(i)) ++count[owner[i]];
      for (types::global_dof_index i = 0; i < n; ++i) {
        if (leader[i] != i || !shared(i)) continue;
        unsigned int best = none;
        for (unsigned int r = 0; r < none; ++r)
          if ((touched[i] >> r & 1) && (best == none || count[r] < count[best])) best = r;
        owner[i] = best;
        ++count[best];
      }
      for (types::global_dof_index i = 0; i < n; ++i) owner[i] = owner[leader[i]];
    }
    std::vector<types::global_dof_index> order(n), renumber(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return owner[a] < owner[b]; });
    for (types::global_dof_index i = 0; i < order.size(); ++i) renumber[order[i]] = i;
    dof.renumber_dofs(renumber);
    owned_begin = static_cast<int>(std::count_if(owner.begin(), owner.end(), [&](unsigned int o) { return o < unsigned(rank); }));
    owned_end = owned_begin + static_cast<int>(std::count(owner.begin(), owner.end(), unsigned(rank)));
  } else {
    owned_begin = 0, owned_end = static_cast<int>(dof.n_dofs());
  }
  cell_rank = part;
  my_cells.clear();
  my_slot.assign(cells, -1);
  for (unsigned int k = 0; k < cells; ++k)
    if (part[k] == unsigned(rank)) {
      my_slot[k] = static_cast<int>(my_cells.size());
      my_cells.push_back(k);
    }
}

void Discretisation::sum_over_ranks(double* data, std::size_t size) const {
  if (ranks == 1) return;
  if (rank == 0) MPI_Reduce(MPI_IN_PLACE, data, static_cast<int>(size), MPI_DOUBLE, MPI_SUM, 0, comm);
  else MPI_Reduce(data, nullptr, static_cast<int>(size), MPI_DOUBLE, MPI_SUM, 0, comm);
  MPI_Bcast(data, static_cast<int>(size), MPI_DOUBLE, 0, comm);
}

bool Discretisation::all_ranks(bool ok) const {
  if (ranks == 1) return ok;
  int flag = ok ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &flag, 1, MPI_INT, MPI_MIN, comm);
  return flag == 1;
}

std::vector<int> Discretisation::dof_components() const {
  std::vector<int> component(dof.n_dofs(), 0);
  std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
  for (const auto& cell : dof.active_cell_iterators()) {
    cell->get_dof_indices(indices);
    for (unsigned int i = 0; i < indices.size(); ++i) component[indices[i]] = fe->system_to_component_index(i).first;
  }
  return component;
}

Discretisation::NearNullSpace Discretisation::near_null_space(const std::vector<bool>& constrained) const {
  std::map<types::global_dof_index, Point<3>> points;
  DoFTools::map_dofs_to_support_points(*mapping, dof, points);
  const std::vector<int> component = dof_components();
  bool nodal = dof.n_dofs() % 3 == 0 && owned_begin % 3 == 0 && owned_end % 3 == 0;
  for (types::global_dof_index i = 0; i < dof.n_dofs() && nodal; ++i)
    nodal = component[i] == static_cast<int>(i % 3) && points.at(i).distance(points.at(i - i % 3)) == 0;
  NearNullSpace out;
  out.node_block = all_ranks(nodal) ? 3 : 1;  // every rank's matrix has the same block size
  Point<3> centre;
  for (const auto& [i, x] : points) centre += x / static_cast<double>(points.size());
  std::vector<std::vector<double>>& modes = out.modes;
  modes.assign(6, std::vector<double>(dof.n_dofs(), 0.0));
  for (const auto& [i, x] : points) {
    if (constrained[i]) continue;
    const int c = component[i];
    const Tensor<1, 3> r = x - centre;
    modes[c][i] = 1;
    for (int a = 0; a < 3; ++a) {  // rotation about axis a: (e_a x r)_c
      Tensor<1, 3> axis;
      axis[a] = 1;
      modes[3 + a][i] = cross_product_3d(axis, r)[c];
    }
  }
  for (std::size_t a = 0; a < modes.size(); ++a) {  // Gram-Schmidt, twice for round-off
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t b = 0; b < a; ++b) {
        const double d = std::inner_product(modes[a].begin(), modes[a].end(), modes[b].begin(), 0.0);
        for (std::size_t i = 0; i < modes[a].size(); ++i) modes[a][i] -= d * modes[b][i];
      }
    const double norm = std::sqrt(std::inner_product(modes[a].begin(), modes[a].end(), modes[a].begin(), 0.0));
    for (double& v : modes[a]) v /= norm;
  }
  return out;
}

std::vector<Discretisation::Piece> Discretisation::pieces(const std::vector<bool>& constrained) const {
  // Pieces: union-find over the vertices of every cell.
  std::vector<unsigned int> parent(tria.n_vertices());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&parent](unsigned int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int v : cell->vertex_indices()) parent[root(cell->vertex_index(v))] = root(cell->vertex_index(0));
  std::map<unsigned int, unsigned int> piece_of_root;
  std::vector<Piece> result;
  std::vector<unsigned int> dof_piece(dof.n_dofs(), 0);
  std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
  for (const auto& cell : dof.active_cell_iterators()) {
    const auto [at, added] = piece_of_root.emplace(root(cell->vertex_index(0)), static_cast<unsigned int>(result.size()));
    if (added) result.emplace_back();
    ++result[at->second].cells;
    cell->get_dof_indices(indices);
    for (const types::global_dof_index i : indices) dof_piece[i] = at->second;
  }
  // Per piece: its centroid and size (to make rotations and translations commensurate), then the
  // Gram matrix of the six modes over its constrained dofs.
  std::map<types::global_dof_index, Point<3>> points;
  DoFTools::map_dofs_to_support_points(*mapping, dof, points);
  const std::vector<int> component = dof_components();
  const std::size_t n = result.size();
  std::vector<Point<3>> centre(n);
  std::vector<double> count(n, 0), size(n, 0);
  for (const auto& [i, x] : points) centre[dof_piece[i]] += x, count[dof_piece[i]] += 1;
  for (std::size_t p = 0; p < n; ++p) centre[p] /= std::max(1.0, count[p]);
  for (const auto& [i, x] : points) size[dof_piece[i]] = std::max(size[dof_piece[i]], x.distance(centre[dof_piece[i]]));
  std::vector<Eigen::Matrix<double, 6, 6>> gram(n, Eigen::Matrix<double, 6, 6>::Zero());
  for (const auto& [i, x] : points) {
    if (!constrained[i]) continue;
    const unsigned int p = dof_piece[i];
    const int c = component[i];
    const Tensor<1, 3> r = (x - centre[p]) / std::max(size[p], 1e-300);
    Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
    row(c) = 1;
    for (int a = 0; a < 3; ++a) {
      Tensor<1, 3> axis;
      axis[a] = 1;
      row(3 + a) = cross_product_3d(axis, r)[c];
    }
    gram[p] += row * row.transpose();
  }
  static const char* const kMotion[6] = {"translation along x", "translation along y", "translation along z",
                                         "rotation about x",    "rotation about y",    "rotation about z"};
  for (std::size_t p = 0; p < n; ++p) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(gram[p]);
    // A held motion has an eigenvalue of the order of the constrained dofs on the piece's scale;
    // a free one vanishes to round-off.
    const double floor = 1e-9 * std::max(1.0, gram[p].trace());
    Eigen::Matrix<double, 6, Eigen::Dynamic> free(6, 0);
    for (int k = 0; k < 6; ++k)
      if (eigen.eigenvalues()(k) < floor) {
        free.conservativeResize(6, free.cols() + 1);
        free.col(free.cols() - 1) = eigen.eigenvectors().col(k);
      }
    int named = 0;
    for (int j = 0; j < 6; ++j)  // a basis motion that lies in the free space (its projection whole)
      if (free.cols() > 0 && (free.transpose() * Eigen::Matrix<double, 6, 1>::Unit(j)).norm() > 1 - 1e-6) {
        result[p].free_motions.emplace_back(kMotion[j]);
        ++named;
      }
    for (int k = named; k < free.cols(); ++k) result[p].free_motions.emplace_back("rotation about the line its supports lie on");
  }
  return result;
}

void Discretisation::build_cells() const {
  Cells& c = cells_;
  c.n = fe->n_dofs_per_cell();
  c.nq = quadrature->size();
  c.nbase = fe->base_element(0).n_dofs_per_cell();
  c.component.resize(c.n);
  c.base.resize(c.n);
  for (unsigned int i = 0; i < c.n; ++i) {
    c.component[i] = fe->system_to_component_index(i).first;
    c.base[i] = fe->system_to_component_index(i).second;
  }
  const unsigned int cells = tria.n_active_cells();
  const std::size_t mine = my_cells.size();
  c.slot = my_slot.data();
  c.indices.resize(mine * c.n);
  c.jxw.resize(mine * c.nq);
  c.gradients.resize(mine * c.nq * c.nbase);
  c.shape_values.resize(std::size_t(c.nq) * c.nbase);
  c.material_id.resize(cells);
  for (unsigned int q = 0; q < c.nq; ++q)
    for (unsigned int b = 0; b < c.nbase; ++b)
      c.shape_values[q * c.nbase + b] = fe->base_element(0).shape_value(b, quadrature->point(q));
  FEValues<3> values(*mapping, *fe, *quadrature, update_gradients | update_JxW_values);
  std::vector<types::global_dof_index> local(c.n);
  unsigned int k = 0;
  for (const auto& cell : dof.active_cell_iterators()) {
    c.material_id[k] = cell->material_id();
    const int slot = my_slot[k++];
    if (slot < 0) continue;
    values.reinit(cell);
    cell->get_dof_indices(local);
    std::copy(local.begin(), local.end(), c.indices.begin() + std::size_t(slot) * c.n);
    for (unsigned int q = 0; q < c.nq; ++q) {
      c.jxw[std::size_t(slot) * c.nq + q] = values.JxW(q);
      for (unsigned int b = 0; b < c.nbase; ++b)
        c.gradients[(std::size_t(slot) * c.nq + q) * c.nbase + b] =
            values.shape_grad_component(fe->component_to_system_index(0, b), q, 0);
    }
  }
  cells_built_ = true;
}

void Discretisation::gather(unsigned int k, const Vector<double>& global, double* local) const {
  const Cells& c = cells();
  const types::global_dof_index* indices = c.dofs(k);
  for (unsigned int i = 0; i < c.n; ++i) local[i] = global[indices[i]];
}

Tensor2 Discretisation::deformation_gradient(unsigned int k, unsigned int q, const double* u_local) const {
  const Cells& c = cells();
  const Tensor<1, 3>* grad = c.gradients_of(k) + q * c.nbase;
  Tensor2 F;
  for (unsigned int i = 0; i < c.n; ++i)
    for (int J = 0; J < 3; ++J) F[c.component[i]][J] += u_local[i] * grad[c.base[i]][J];
  for (int d = 0; d < 3; ++d) F[d][d] += 1;
  return F;
}

}  // namespace fetouch::fem
