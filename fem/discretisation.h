// The discretisation of a body: its mesh, the vector-valued finite element (P1/P2 on tetrahedra,
// Q1/Q2 on hexahedra), the degrees of freedom, their split among MPI ranks, and what a total
// Lagrangian assembly needs of every cell and never recomputes: dof indices, JxW and the reference
// gradients of the scalar base functions at each quadrature point.
//
// MPI: every rank holds the whole mesh and state; METIS splits the cells (each rank assembles its
// own) and the dofs are renumbered rank by rank so that each rank owns a contiguous block of rows.
#pragma once

#include <deal.II/base/quadrature.h>
#include <deal.II/base/tensor.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/vector.h>
#include <mpi.h>

#include <array>
#include <cassert>
#include <memory>
#include <string>
#include <vector>

#include "fem/material.h"

namespace fetouch::fem {

class Discretisation {
 public:
  // Throws std::invalid_argument for a degree other than 1 or 2, or a mixed mesh.
  Discretisation(const dealii::Triangulation<3>& triangulation, int degree, MPI_Comm comm);

  const dealii::Triangulation<3>& tria;
  bool simplex = true;
  std::unique_ptr<dealii::FiniteElement<3>> fe;
  std::unique_ptr<dealii::Mapping<3>> mapping;
  std::unique_ptr<dealii::Quadrature<3>> quadrature;
  std::unique_ptr<dealii::Quadrature<2>> face_quadrature;
  dealii::DoFHandler<3> dof;

  MPI_Comm comm;
  int rank = 0, ranks = 1;
  std::vector<unsigned int> my_cells;   // indices (in cell order) of the cells this rank assembles
  std::vector<unsigned int> cell_rank;  // the rank of every cell
  std::vector<int> my_slot;             // cell k's place in my_cells; -1 for another rank's cell
  int owned_begin = 0, owned_end = 0;   // this rank's rows

  unsigned int n_dofs() const { return static_cast<unsigned int>(dof.n_dofs()); }
  unsigned int n_cells() const { return tria.n_active_cells(); }

  // Sums a vector's per-rank parts onto every rank, bitwise the same everywhere (reduced on rank 0,
  // then broadcast: a rank that rounded differently would take other Newton decisions).
  void sum_over_ranks(double* data, std::size_t size) const;
  // True on every rank iff `ok` on every rank.
  bool all_ranks(bool ok) const;

  // The displacement component of every dof.
  std::vector<int> dof_components() const;
  // What algebraic multigrid is told: the rigid-body modes (3 translations, 3 rotations about the
  // centroid), orthonormal, zero on constrained dofs; and the dofs a node, 3 when they come in
  // threes, the x, y and z of one point together (dofs 3k, 3k+1, 3k+2), and every rank's rows start
  // and end at a node (1 otherwise): multigrid then aggregates nodes.
  struct NearNullSpace {
    std::vector<std::vector<double>> modes;
    int node_block = 1;
  };
  NearNullSpace near_null_space(const std::vector<bool>& constrained) const;

  // The body's pieces (cells joined through shared vertices), each with the rigid motions that the
  // constrained dofs leave free ("translation along x", "rotation about z", or "rotation about the
  // line its supports lie on"): none for a piece that is held. From the Gram matrix of the six
  // rigid-body modes sampled at the piece's constrained dofs: a motion is free where it vanishes.
  struct Piece {
    unsigned int cells = 0;
    std::vector<std::string> free_motions;
  };
  std::vector<Piece> pieces(const std::vector<bool>& constrained) const;

  // The per-cell data of a total Lagrangian assembly (built on first use), kept for the cells this
  // rank assembles only (my_cells, in their order: all cells on one rank); cell k's is at its slot
  // (my_slot[k]), which dofs(k), jxw_of(k) ([q]) and gradients_of(k) ([q * nbase + base]) look up. Asking for another rank's
  // cell is a logic error (unchecked: the assembly's inner loop asks).
  struct Cells {
    unsigned int n = 0, nq = 0, nbase = 0;       // dofs per cell, quadrature points, scalar base functions
    std::vector<unsigned int> component, base;   // of each cell dof
    std::vector<dealii::types::global_dof_index> indices;  // [slot][i]
    std::vector<double> jxw;                     // [slot][q]
    std::vector<dealii::Tensor<1, 3>> gradients;  // [slot][q][base], reference
    std::vector<double> shape_values;            // [q][base], the same on every cell
    std::vector<dealii::types::material_id> material_id;  // [cell], every cell's
    const int* slot = nullptr;                   // Discretisation::my_slot

    std::size_t at(unsigned int k) const {
      assert(slot[k] >= 0);
      return static_cast<std::size_t>(slot[k]);
    }
    const dealii::types::global_dof_index* dofs(unsigned int k) const { return &indices[at(k) * n]; }
    const double* jxw_of(unsigned int k) const { return &jxw[at(k) * nq]; }
    const dealii::Tensor<1, 3>* gradients_of(unsigned int k) const { return &gradients[at(k) * nq * nbase]; }
  };
  const Cells& cells() const {
    if (!cells_built_) build_cells();
    return cells_;
  }

  // Every boundary face of the mesh, in cell order and then face order (as a walk over all cells
  // and their faces meets them), with what the searches over the surface need of it: a probe's
  // patch (fem/contact_patches.cc) and the boundary point nearest a probe (fem/boundary_geometry.cc).
  // Built with the discretisation: walking every cell's faces for each search took about 1 ms of a
  // 17 ms frame while two hands slid (the Leopold exercise, 6,477 DOFs).
  struct BoundaryFace {
    dealii::DoFHandler<3>::active_cell_iterator cell;
    unsigned int face = 0;
    dealii::Point<3> center;   // reference configuration
    double diameter = 0;
    unsigned int vertices = 0;  // 3 or 4
    std::array<dealii::Point<3>, 4> vertex;  // reference positions
    std::array<dealii::types::global_dof_index, 12> vertex_dof;  // [vertex * 3 + component]
  };
  const std::vector<BoundaryFace>& boundary_faces() const { return boundary_faces_; }

  // Cell k's entries of a global vector (k one of my_cells).
  void gather(unsigned int k, const dealii::Vector<double>& global, double* local) const;
  // F = I + grad u at quadrature point q of cell k, from the cell's local displacements.
  Tensor2 deformation_gradient(unsigned int k, unsigned int q, const double* u_local) const;

 private:
  void partition();
  void build_cells() const;
  std::vector<BoundaryFace> boundary_faces_;
  mutable Cells cells_;
  mutable bool cells_built_ = false;
};

}  // namespace fetouch::fem
