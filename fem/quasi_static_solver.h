// A hyperelastic body in total Lagrangian form, solved quasi-statically (or one time step per solve
// with inertia): find the displacement u with
//   R(u) = int_Omega P(I + grad u) : grad v dV - (loads) . v = 0   for all admissible v,
// prescribed displacements on named boundary regions (per component), the loads applied in steps.
// Solves continue: a second solve() starts from the first one's state and moves the loads from
// their converged values to the new ones (a frame of the haptic loop changes the probe forces).
//
// This class composes the parts, one concept each (fem/README.md): the discretisation
// (discretisation.h), the terms of the weak form, each built only when asked for (elasticity_term.h,
// external_loads.h, inertia_term.h, cavity_term.h, contact_patches.h), the Newton driver that
// iterates over them (newton_driver.h), the linear systems (linear_system.h, tangent_system.h), the
// condensed compliance (condensed_compliance.h), boundary geometry (boundary_geometry.h) and output
// (solver_output.cc). Its interface is the one the environment, the commands and the tests use.
//
// Elements: P1/P2 on tetrahedra, Q1/Q2 on hexahedra, chosen from the triangulation's cells and the
// degree. MPI: all ranks of the communicator step together (MPI must be initialised, by a
// fem::MpiSession in main).
#pragma once

#include <deal.II/base/tensor.h>
#include <deal.II/grid/tria.h>
#include <deal.II/lac/full_matrix.h>
#include <mpi.h>

#include <array>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "fem/cavity.h"
#include "fem/condensed_compliance.h"
#include "fem/inertia_term.h"
#include "fem/material.h"
#include "fem/newton_driver.h"

namespace fetouch::fem {

// Where a frame's time went, one line: its Newton iterations and phases, and its compliance's.
std::string describe_frame(const SolveReport& solve, const ComplianceTimes& compliance);

class QuasiStaticSolver {
 public:

  // All ranks of `comm` step the solver together, each with the whole mesh and state; the cells are
  // split among them by METIS for assembly and the tangent's rows for the linear algebra (MUMPS or
  // AMG in parallel). One rank: serial.
  QuasiStaticSolver(const dealii::Triangulation<3>& triangulation, const Material& material, int degree,
                    MPI_Comm comm = MPI_COMM_WORLD);
  ~QuasiStaticSolver();
  int ranks() const;
  // Linear solves by CG with algebraic multigrid (aggregation of nodes, rigid-body near-null space) instead of CG
  // on a stale sparse Cholesky factorisation: for meshes too large to factorise.
  void use_algebraic_multigrid(bool on);
  // Threads assembling the elasticity (1 or 2, the default; elasticity_term.h).
  void set_assembly_threads(unsigned int threads);
  // Whether a background factorisation is waited for at the frame it is due (true: reproducible,
  // the default, and what lockstep replays use) or, when not ready there, taken up at the first
  // frame after at which it is (real time; the worker then yields its core to the frames).
  // tangent_system.h.
  void set_deterministic_factorisations(bool on);
  // Solves so far that went on without a due background factorisation (not deterministic): each
  // differs from what lockstep solves within the solve's tolerance, and so may every one after it.
  int late_background_frames() const;
  // AMG's levels as set up last, fine first (rows, nonzeros); empty on the direct path.
  std::vector<TangentSystem::Level> multigrid_levels() const;
  QuasiStaticSolver(QuasiStaticSolver&&) noexcept;
  QuasiStaticSolver& operator=(QuasiStaticSolver&&) noexcept;

  // u = value (at load factor 1) on the components selected by `components`, on a boundary region.
  void prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                              const dealii::Tensor<1, 3>& value);
  // The same with a displacement field g(x) (at load factor 1).
  void prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                              std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&)> field);
  // Cells with this material id (a Gmsh physical volume) take `material` instead of the body's
  // (kept by reference; it must outlive the solver).
  void set_region_material(unsigned int material_id, const Material& material);
  // A dead-load traction (force per reference area, N/m^2) on a boundary region.
  void apply_traction(unsigned int boundary_id, const dealii::Tensor<1, 3>& traction);

  // A body force per reference volume (N/m^3) as a field, scaled by the load factor.
  void apply_body_force(std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&)> force);
  // The same, per material id (a density per region).
  void apply_body_force(std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&, unsigned int material_id)> force);

  SolveReport solve(const NewtonSettings& settings);

  // Nearly incompressible tissue without volumetric locking: the volumetric energy U(J) of a
  // decoupled material is taken of each cell's volume ratio theta = (1/V) int J dV instead of J
  // pointwise, i.e. a displacement-pressure formulation with the pressure constant per cell,
  // condensed (Q1/P0, P2/P0; Simo, Taylor and Pister's mean dilatation). Throws
  // std::invalid_argument for a coupled material. (P1 tetrahedra have one point: no change.)
  void use_mean_dilatation(bool on);

  // A fluid-filled cavity bounded by the boundary faces of `boundary_id` (an inner surface, closed;
  // quadratic elements' faces curved through their nodes), its pressure following its volume by
  // `law` (fem/cavity.h). The pressure is part of the body's response: it is not scaled by load
  // steps. Throws std::invalid_argument for a surface that encloses no volume or a second cavity.
  void add_cavity(unsigned int boundary_id, const CavityLaw& law);
  // A cavity that is the cells of the material ids `contents` (amniotic fluid and the fetus in it,
  // meshed as solids): the law holds for their total volume, and its pressure acts on the wall
  // around them (cavity_term.h). The same exceptions, and for no such cells.
  void add_cavity(const std::set<unsigned int>& contents, const CavityLaw& law);
  double cavity_volume() const;            // m^3, at the current state (0 without a cavity)
  double cavity_reference_volume() const;  // m^3
  double cavity_pressure() const;          // Pa

  // Inertia and Rayleigh damping (inertia_term.h): once enabled, each solve() is one time step of
  // length dt. Throws std::invalid_argument for a non-positive time step or density, or negative
  // damping coefficients.
  using Dynamics = fem::Dynamics;
  void enable_dynamics(const Dynamics& dynamics);

  // Contact patches (contact_patches.h): a probe's force spread by a smooth kernel over its radius.
  // Returns the patch's index.
  int add_contact_patch(const dealii::Point<3>& center, double radius);
  void set_patch_force(int patch, const dealii::Tensor<1, 3>& force);  // scaled by the load factor
  // Moves a patch's centre (reference coordinates) and rebuilds its kernel; its force stays. Throws
  // std::invalid_argument (and leaves the patch as it was) with no boundary within its radius.
  void move_contact_patch(int patch, const dealii::Point<3>& center);
  // The reference point X of the boundary whose deformed position X + u(X) is nearest x (or, with
  // deformed = false, whose reference position is): over the boundary faces (quadrilaterals as two
  // triangles) with u linear between the vertices' values.
  dealii::Point<3> boundary_point_nearest(const dealii::Point<3>& x, bool deformed = true) const;
  dealii::Tensor<1, 3> patch_displacement(int patch) const;
  // The patch centre and its displacement, and the deformed outward normal there: the kernel-
  // weighted average of the deformed face normals (Nanson: n da = J F^-T N dA), normalised.
  dealii::Point<3> patch_center(int patch) const;
  dealii::Tensor<1, 3> patch_normal(int patch) const;
  int patches() const;
  double patch_radius(int patch) const;
  // The condensed compliance at the current state: W = H K^-1 H' (3m x 3m, m/N; row/column 3a + c
  // is patch a, component c), K the consistent tangent with the supports (after a converged solve,
  // the one Newton ended with: no new assembly). The 3m columns K^-1 h are solved to
  // kComplianceTolerance, or, when the last compliance's columns still span them (a Galerkin
  // update with residual under kGalerkinTolerance), updated without a solve. Symmetric positive
  // definite when the body is supported.
  dealii::FullMatrix<double> compliance();
  const ComplianceTimes& last_compliance_times() const;
  // The relative error of W a Galerkin update may leave (its residual's square): by default 1e-6.
  void set_compliance_accuracy(double relative_error);

  // The reaction of a boundary region: the force its supports exert on the body, i.e. internal
  // minus external nodal forces summed over the region's degrees of freedom, per component (at
  // equilibrium that sum vanishes on free degrees of freedom).
  dealii::Tensor<1, 3> boundary_force(unsigned int boundary_id) const;
  // u at a point (found by search; throws if outside the mesh).
  dealii::Tensor<1, 3> displacement_at(const dealii::Point<3>& point) const;
  // Largest |u(x) - g(x)| over the mesh's support points, g given per support point.
  double max_nodal_error(const std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&)>& exact) const;

  // The L2 norm of u - exact over the body (Gauss quadrature two orders above the element's).
  double l2_error(const std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&)>& exact) const;

  unsigned int dofs() const;
  unsigned int cells() const;
  // What each rank holds of the partition, in rank order, on every rank (collective): the cells it
  // assembles and the tangent rows (dofs) it owns.
  struct Share {
    unsigned int cells = 0, dofs = 0;
  };
  std::vector<Share> shares() const;
  // The body's pieces and the rigid motions its supports leave free on each (Discretisation::pieces):
  // a piece with a free motion is not held, and a load on it has no equilibrium.
  std::vector<Discretisation::Piece> pieces();
  // The terms a solve assembles, in order (elasticity always; the others only once asked for).
  std::vector<std::string> terms() const;

  // Per-cell figures of the current state (averages over the cell's quadrature points), every
  // cell's, in cell order (collective under MPI: each rank computes its own cells', and every rank
  // calls it).
  struct CellFields {
    std::vector<double> jacobian;   // J = det F
    std::vector<double> von_mises;  // of the Cauchy stress, Pa
  };
  CellFields cell_fields() const;
  double max_displacement() const;  // largest nodal |u|, m

  // The mesh as a viewer draws it (the trainer): the triangulation's vertices (reference
  // positions, m), its cells as tetrahedra (a hexahedron split in six, through its 0-7 diagonal)
  // with each one's material id, and its boundary faces as triangles (a quadrilateral split in two).
  struct DrawingMesh {
    std::vector<std::array<double, 3>> points;
    std::vector<std::array<unsigned int, 4>> tetrahedra;
    std::vector<unsigned int> tetrahedron_cell;  // the cell each tetrahedron belongs to
    std::vector<unsigned int> material;          // per tetrahedron
    std::vector<std::array<unsigned int, 3>> boundary_triangles;
    std::vector<unsigned int> boundary_triangle_cell;  // the cell each boundary triangle bounds
  };
  DrawingMesh drawing_mesh() const;
  // The current displacement at the mesh's vertices: 3 values per DrawingMesh point (x, y, z), m.
  // `out` is resized only when its size is not that; vertices no cell uses get 0.
  void vertex_displacements(std::vector<float>& out) const;

  // The deformed state for ParaView: a VTU with the displacement (warp by vector to see the
  // deformation), J and the von Mises stress per cell. Throws std::runtime_error if unwritable.
  void write_vtu(const std::string& path) const;
  // In parallel: every rank writes the cells it assembles as DIRECTORY/NAME_CCCC.RRRR.vtu, rank 0 the
  // DIRECTORY/NAME_CCCC.pvtu that gathers them (collective; returns the .pvtu's file name).
  std::string write_vtu_pieces(const std::string& directory, const std::string& name, unsigned int counter) const;

  // The parts (fem/solver_parts.h), for fem/'s own translation units.
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace fetouch::fem
