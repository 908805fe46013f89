#include "fem/quasi_static_solver.h"

#include "fem/cavity.h"
#include "fem/tangent_system.h"

#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_simplex_p.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_fe.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_component_interpretation.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <limits>
#include <stdexcept>
#include <thread>

namespace fetouch::fem {

using namespace dealii;

struct QuasiStaticSolver::Impl {
  const Triangulation<3>& tria;
  const Material& material;
  std::map<types::material_id, const Material*> region_materials;  // set_region_material
  std::vector<const Material*> cell_material;                      // per active cell, in cache order
  bool simplex;
  std::unique_ptr<FiniteElement<3>> fe;
  std::unique_ptr<Mapping<3>> mapping;
  std::unique_ptr<Quadrature<3>> quadrature;
  std::unique_ptr<Quadrature<2>> face_quadrature;
  DoFHandler<3> dof;
  AffineConstraints<double> constraints;  // homogeneous: the Newton update's
  std::vector<bool> constrained;          // per dof
  bool tangent_current = false;           // the tangent's values are those of the current state
  Vector<double> u;

  struct Prescribed {
    unsigned int boundary;
    std::array<bool, 3> components;
    std::function<Tensor<1, 3>(const Point<3>&)> field;
  };
  // g(x) scaled by the load factor, as a deal.II Function.
  class ScaledField : public Function<3> {
   public:
    ScaledField(const std::function<Tensor<1, 3>(const Point<3>&)>& field, double lambda)
        : Function<3>(3), field_(field), lambda_(lambda) {}
    double value(const Point<3>& p, const unsigned int component) const override {
      return lambda_ * field_(p)[component];
    }
   private:
    const std::function<Tensor<1, 3>(const Point<3>&)>& field_;
    double lambda_;
  };
  struct Traction {
    unsigned int boundary;
    Tensor<1, 3> value;
  };
  std::vector<Prescribed> prescribed;
  std::vector<Traction> tractions;
  std::function<Tensor<1, 3>(const Point<3>&)> body_force;
  struct Patch {
    Point<3> center;
    double radius;
    std::array<Vector<double>, 3> h;  // H rows, one per component
    Tensor<1, 3> force;
    Tensor<1, 3> converged_force;     // the force of the last converged solve
  };
  // Loads at factor lambda run from the last converged solve's to the new ones: the static loads
  // (supports, tractions, body force) from `static_done` (0 before the first solve, 1 after) to
  // full, patch forces from their converged value to the new one. A solve thus continues from the
  // previous frame's state and loads (warm start).
  double static_done = 0;
  double static_factor(double lambda) const { return static_done + lambda * (1 - static_done); }
  std::vector<Patch> patches;
  int linear_iterations = 0;
  std::vector<Vector<double>> compliance_columns;  // K^-1 H' of the last compliance: warm starts
  // Phase timers of the running solve, and of the last compliance.
  double assembly_s = 0, factorisation_s = 0, solve_s = 0;
  ComplianceTimes compliance_times;
  static double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // MPI: every rank holds the mesh and the state; the cells are split by METIS, each rank assembling
  // its own (the sums are reduced onto all ranks), and the tangent's rows are split with them.
  MPI_Comm comm;
  int rank = 0, ranks = 1;
  std::vector<unsigned int> my_cells;  // indices (in cell order) of the cells this rank assembles
  std::vector<unsigned int> cell_rank;  // the rank of every cell
  int owned_begin = 0, owned_end = 0;   // this rank's rows
  TangentSystem::Method linear_method = TangentSystem::Method::factorisation;
  TangentSystem tangent;

  Impl(const Triangulation<3>& t, const Material& m, int degree, MPI_Comm c)
      : tria(t), material(m), dof(t), comm(c), tangent(c) {
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
    u.reinit(dof.n_dofs());
  }

  // METIS splits the cells (computed on rank 0, broadcast: every rank must agree); each dof goes to
  // the lowest rank among its cells', and dofs are renumbered rank by rank so that each rank owns a
  // contiguous block of rows.
  void partition() {
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
      std::vector<unsigned int> owner(dof.n_dofs(), static_cast<unsigned int>(ranks));
      std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
      unsigned int k = 0;
      for (const auto& cell : dof.active_cell_iterators()) {
        cell->get_dof_indices(indices);
        for (const auto i : indices) owner[i] = std::min(owner[i], part[k]);
        ++k;
      }
      std::vector<types::global_dof_index> order(dof.n_dofs()), renumber(dof.n_dofs());
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
    for (unsigned int k = 0; k < cells; ++k)
      if (part[k] == unsigned(rank)) my_cells.push_back(k);
  }

  // Sums a vector's per-rank parts onto every rank, bitwise the same everywhere (reduced on rank 0,
  // then broadcast: a rank that rounded differently would take other Newton decisions).
  void sum_over_ranks(double* data, std::size_t size) const {
    if (ranks == 1) return;
    if (rank == 0) MPI_Reduce(MPI_IN_PLACE, data, static_cast<int>(size), MPI_DOUBLE, MPI_SUM, 0, comm);
    else MPI_Reduce(data, nullptr, static_cast<int>(size), MPI_DOUBLE, MPI_SUM, 0, comm);
    MPI_Bcast(data, static_cast<int>(size), MPI_DOUBLE, 0, comm);
  }
  bool all_ranks(bool ok) const {
    if (ranks == 1) return ok;
    int flag = ok ? 1 : 0;
    MPI_Allreduce(MPI_IN_PLACE, &flag, 1, MPI_INT, MPI_MIN, comm);
    return flag == 1;
  }

  // The displacement component of every dof (whatever the numbering).
  std::vector<int> dof_components() const {
    std::vector<int> component(dof.n_dofs(), 0);
    std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
    for (const auto& cell : dof.active_cell_iterators()) {
      cell->get_dof_indices(indices);
      for (unsigned int i = 0; i < indices.size(); ++i) component[indices[i]] = fe->system_to_component_index(i).first;
    }
    return component;
  }

  // The rigid-body modes (3 translations, 3 rotations about the centroid), zero on constrained dofs:
  // algebraic multigrid's near-null space.
  std::vector<std::vector<double>> rigid_body_modes() const {
    std::map<types::global_dof_index, Point<3>> points;
    DoFTools::map_dofs_to_support_points(*mapping, dof, points);
    const std::vector<int> component = dof_components();
    Point<3> centre;
    for (const auto& [i, x] : points) centre += x / static_cast<double>(points.size());
    std::vector<std::vector<double>> modes(6, std::vector<double>(dof.n_dofs(), 0.0));
    for (const auto& [i, x] : points) {
      if (constrained[i]) continue;
      const int c = component[i];
      const Tensor<1, 3> r = x - centre;
      modes[c][i] = 1;
      // rotation about axis a: (e_a x r)_c
      for (int a = 0; a < 3; ++a) {
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
    return modes;
  }

  bool set_up = false;  // constraints and sparsity for the current supports
  void setup_constraints() {
    if (set_up) return;
    set_up = true;
    constraints.clear();
    std::set<types::boundary_id> present;
    for (const auto& face : tria.active_face_iterators())
      if (face->at_boundary()) present.insert(face->boundary_id());
    for (const Prescribed& p : prescribed)
      if (!present.count(p.boundary))
        throw std::invalid_argument("prescribed displacement: no boundary face has id " + std::to_string(p.boundary));
    for (const Prescribed& p : prescribed)
      VectorTools::interpolate_boundary_values(*mapping, dof, p.boundary, Functions::ZeroFunction<3>(3), constraints,
                                               ComponentMask({p.components[0], p.components[1], p.components[2]}));
    constraints.close();
    constrained.assign(dof.n_dofs(), false);
    for (types::global_dof_index i = 0; i < dof.n_dofs(); ++i) constrained[i] = constraints.is_constrained(i);
    // Couplings of free dofs, and the diagonal of constrained ones.
    DynamicSparsityPattern dsp(dof.n_dofs());
    DoFTools::make_sparsity_pattern(dof, dsp);
    std::vector<int> row_start{0}, columns;
    for (types::global_dof_index i = 0; i < dof.n_dofs(); ++i) {
      for (auto entry = dsp.begin(i); entry != dsp.end(i); ++entry) {
        const types::global_dof_index j = entry->column();
        if (i == j || (!constrained[i] && !constrained[j])) columns.push_back(static_cast<int>(j));
      }
      row_start.push_back(static_cast<int>(columns.size()));
    }
    const bool amg = linear_method == TangentSystem::Method::amg;
    tangent.set_pattern(std::move(row_start), std::move(columns), linear_method, owned_begin, owned_end,
                        amg ? rigid_body_modes() : std::vector<std::vector<double>>{});
    scatter.clear();
    tangent_current = false;
    compliance_columns.clear();
  }

  // u on the prescribed components := lambda * value.
  void apply_prescribed(double lambda) {
    for (const Prescribed& p : prescribed) {
      std::map<types::global_dof_index, double> values;
      VectorTools::interpolate_boundary_values(*mapping, dof, p.boundary, ScaledField(p.field, static_factor(lambda)), values,
                                               ComponentMask({p.components[0], p.components[1], p.components[2]}));
      for (const auto& [index, value] : values) u[index] = value;
    }
  }

  // The residual r = f_ext(lambda) - f_int(u), constrained entries zero, and (if `tangent`) K.
  // `internal`, if given, receives f_int without constraints (for reactions). False if J <= 0.
  bool assemble(double lambda, Vector<double>& r, bool tangent, Vector<double>* internal = nullptr) {
    const auto start = std::chrono::steady_clock::now();
    const bool ok = assemble_impl(lambda, r, tangent, internal);
    assembly_s += since(start);
    return ok;
  }

  // What never changes in a total Lagrangian formulation, computed once: per cell its dof indices,
  // JxW and the reference gradients of the scalar base functions at each quadrature point, and the
  // external load vector of the tractions and the body force (at full load).
  struct Cache {
    bool built = false;
    unsigned int n = 0, nq = 0, nbase = 0;
    std::vector<unsigned int> component, base;  // of each cell dof
    std::vector<types::global_dof_index> indices;
    std::vector<double> jxw;
    std::vector<Tensor<1, 3>> gradients;  // [cell][q][base]
    std::vector<double> shape_values;     // [q][base]: reference values, the same on every cell
    Vector<double> external;
  } cache;

  bool mean_dilatation = false;

  // The fluid-filled cavity (add_cavity), its state at the last assembly, and y = K_s^-1 g for the
  // Sherman-Morrison solves with K = K_s + c g g' (K_s the sparse part, c = -dp/dV >= 0).
  struct Cavity {
    bool active = false;
    unsigned int boundary = 0;
    CavityLaw law;
    CavityWall wall;
    double reference_volume = 0, stiffness = 0;
    double pressure = 0;         // an unknown of the solve, beside u
    double volume_residual = 0;  // V(u) - V_law(p), m^3
    Vector<double> g, y;
    bool y_current = false;
  } cavity;

  void build_cavity_wall() {
    Cavity& cv = cavity;
    cv.wall.triangles.clear();
    std::vector<types::global_dof_index> indices(fe->n_dofs_per_cell());
    for (const auto& cell : dof.active_cell_iterators())
      for (const unsigned int f : cell->face_indices()) {
        const auto face = cell->face(f);
        if (!face->at_boundary() || face->boundary_id() != cv.boundary) continue;
        const unsigned int nv = face->n_vertices();
        cell->get_dof_indices(indices);
        const auto triangle = [&](unsigned int a, unsigned int b, unsigned int c) {
          CavityWall::Triangle t;
          const unsigned int vs[3] = {a, b, c};
          for (int v = 0; v < 3; ++v) {
            // The face vertex's index in the cell, then its dof of each component.
            unsigned int in_cell = 0;
            while (cell->vertex_index(in_cell) != face->vertex_index(vs[v])) ++in_cell;
            for (unsigned int d = 0; d < 3; ++d) {
              t.dofs[v][d] = static_cast<unsigned int>(indices[fe->component_to_system_index(d, in_cell)]);
              t.position[v][d] = face->vertex(vs[v])[d];
            }
          }
          // Normals out of the cavity, i.e. into this cell.
          const Point<3> pa = face->vertex(a), pb = face->vertex(b), pc = face->vertex(c);
          const Tensor<1, 3> normal = cross_product_3d(pb - pa, pc - pa);
          if (normal * (cell->center() - face->center()) < 0) std::swap(t.dofs[1], t.dofs[2]), std::swap(t.position[1], t.position[2]);
          cv.wall.triangles.push_back(t);
        };
        if (nv == 3) {
          triangle(0, 1, 2);
        } else {  // deal.II's quadrilateral vertices 0, 1, 3, 2 go around the face
          triangle(0, 1, 3);
          triangle(0, 3, 2);
        }
      }
    if (cv.wall.triangles.empty())
      throw std::invalid_argument("cavity: no boundary face has the cavity's boundary id " + std::to_string(cv.boundary));
    const Vector<double> zero(dof.n_dofs());
    cv.reference_volume = cv.wall.volume(zero.begin());
    if (!(cv.reference_volume > 0))
      throw std::invalid_argument("cavity: the surface with boundary id " + std::to_string(cv.boundary) +
                                  " does not enclose a volume (not closed, or not an inner surface)");
    cv.g.reinit(dof.n_dofs());
    cv.y.reinit(dof.n_dofs());
  }

  // The cavity's load p g into r (and -p g into `internal`), and -p d2V into the tangent, with the
  // pressure p an unknown beside u, and the law's residual V(u) - V_law(p); false if the cavity
  // collapsed (V <= 0). (Taking p = p(V(u)) instead, a liquid's stiffness K/V0 ~ 1e13 Pa/m^3
  // turns any second-order volume error of a step into a huge force: Newton stalls.)
  bool assemble_cavity(Vector<double>& r, bool with_tangent, Vector<double>* internal) {
    Cavity& cv = cavity;
    const double volume = cv.wall.volume(u.begin());
    if (!(volume > 0)) return false;
    const double p = cv.pressure;
    cv.volume_residual = volume - cv.law.volume(p, cv.reference_volume);
    cv.g = 0;
    cv.wall.add_gradient(u.begin(), 1.0, cv.g.begin());
    for (types::global_dof_index i = 0; i < u.size(); ++i) {
      if (internal) (*internal)[i] -= p * cv.g[i];
      if (constrained[i]) cv.g[i] = 0;
      else r[i] += p * cv.g[i];
    }
    if (with_tangent) {
      cv.wall.add_hessian(u.begin(), -p, [&](unsigned int row, unsigned int column, double value) {
        if (!constrained[row] && !constrained[column]) tangent.add(static_cast<int>(row), static_cast<int>(column), value);
      });
      cv.stiffness = -1 / cv.law.volume_derivative(p, cv.reference_volume);  // -dp/dV of the law
      cv.y_current = false;
    }
    return true;
  }

  // y = K x with the cavity's rank-one part.
  void multiply(const Vector<double>& x, Vector<double>& y) const {
    tangent.multiply(x.begin(), y.begin());
    if (cavity.active && cavity.stiffness != 0) y.add(cavity.stiffness * (cavity.g * x), cavity.g);
  }

  // Time stepping (enable_dynamics): the state at the start of the step and the step's constants.
  bool dynamic = false;
  QuasiStaticSolver::Dynamics dynamics;
  Vector<double> u_old, v_old, a_old;
  // a+ = c0 (u+ - u_old) - c1 v_old - c2 a_old;   v+ = v_old + dv_base + dv_gain a+  (Newmark)
  //                                               v+ = (u+ - u_old)/dt               (backward Euler)
  double c0 = 0, c1 = 0, c2 = 0;
  void step_constants() {
    const double dt = dynamics.time_step_s;
    if (dynamics.newmark) {
      c0 = 1 / (dynamics.beta * dt * dt), c1 = 1 / (dynamics.beta * dt), c2 = (1 - 2 * dynamics.beta) / (2 * dynamics.beta);
    } else {
      c0 = 1 / (dt * dt), c1 = 1 / dt, c2 = 0;
    }
  }
  double acceleration(double u_new, types::global_dof_index i) const {
    return c0 * (u_new - u_old[i]) - c1 * v_old[i] - c2 * a_old[i];
  }
  double velocity(double u_new, double a_new, types::global_dof_index i) const {
    const double dt = dynamics.time_step_s;
    if (dynamics.newmark) return v_old[i] + dt * ((1 - dynamics.gamma) * a_old[i] + dynamics.gamma * a_new);
    return (u_new - u_old[i]) / dt;
  }
  // dv+/du+, and d(a + alpha v)/du+ for the tangent.
  double velocity_gain() const { return dynamics.newmark ? dynamics.gamma * dynamics.time_step_s * c0 : 1 / dynamics.time_step_s; }
  double inertia_gain() const { return c0 + dynamics.rayleigh_mass_per_s * velocity_gain(); }

  // beta K0 for stiffness-proportional damping: the tangent's values at the reference state, the
  // constrained rows' diagonal left out (built by the first dynamic solve).
  std::vector<double> reference_stiffness;
  void build_reference_stiffness() {
    const Vector<double> state = u;
    const bool was_dynamic = dynamic;
    u = 0;
    dynamic = false;
    Vector<double> r(u.size());
    const bool ok = assemble(0.0, r, /*tangent=*/true);
    u = state;
    dynamic = was_dynamic;
    tangent_current = false;
    if (!ok) throw std::runtime_error("stiffness damping: the reference state's tangent could not be assembled");
    reference_stiffness.assign(tangent.values(), tangent.values() + tangent.nonzeros());
    for (types::global_dof_index i = 0; i < u.size(); ++i)
      if (constrained[i]) reference_stiffness[tangent.position(static_cast<int>(i), static_cast<int>(i))] = 0;
  }

  void build_cache() {
    Cache& c = cache;
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
    c.indices.resize(std::size_t(cells) * c.n);
    c.jxw.resize(std::size_t(cells) * c.nq);
    c.gradients.resize(std::size_t(cells) * c.nq * c.nbase);
    c.shape_values.resize(std::size_t(c.nq) * c.nbase);
    for (unsigned int q = 0; q < c.nq; ++q)
      for (unsigned int b = 0; b < c.nbase; ++b)
        c.shape_values[q * c.nbase + b] = fe->base_element(0).shape_value(b, quadrature->point(q));
    c.external.reinit(dof.n_dofs());
    FEValues<3> values(*mapping, *fe, *quadrature,
                       update_gradients | update_JxW_values | update_values | update_quadrature_points);
    FEFaceValues<3> face_values(*mapping, *fe, *face_quadrature, update_values | update_JxW_values);
    std::vector<types::global_dof_index> local(c.n);
    Vector<double> cell_external(c.n);
    unsigned int k = 0;
    cell_material.assign(cells, &material);
    for (const auto& cell : dof.active_cell_iterators()) {
      const auto region = region_materials.find(cell->material_id());
      if (region != region_materials.end()) cell_material[k] = region->second;
      values.reinit(cell);
      cell->get_dof_indices(local);
      std::copy(local.begin(), local.end(), c.indices.begin() + std::size_t(k) * c.n);
      for (unsigned int q = 0; q < c.nq; ++q) {
        c.jxw[std::size_t(k) * c.nq + q] = values.JxW(q);
        for (unsigned int b = 0; b < c.nbase; ++b)
          c.gradients[(std::size_t(k) * c.nq + q) * c.nbase + b] =
              values.shape_grad_component(fe->component_to_system_index(0, b), q, 0);
      }
      cell_external = 0;
      if (body_force)
        for (unsigned int q = 0; q < c.nq; ++q) {
          const Tensor<1, 3> f = body_force(values.quadrature_point(q));
          for (unsigned int i = 0; i < c.n; ++i)
            cell_external(i) += f[c.component[i]] * values.shape_value_component(i, q, c.component[i]) * values.JxW(q);
        }
      for (const unsigned int f : cell->face_indices()) {
        if (!cell->face(f)->at_boundary()) continue;
        for (const Traction& t : tractions) {
          if (cell->face(f)->boundary_id() != t.boundary) continue;
          face_values.reinit(cell, f);
          for (unsigned int q = 0; q < face_quadrature->size(); ++q)
            for (unsigned int i = 0; i < c.n; ++i)
              cell_external(i) += t.value[c.component[i]] * face_values.shape_value_component(i, q, c.component[i]) *
                                  face_values.JxW(q);
        }
      }
      c.external.add(local, cell_external);
      ++k;
    }
    c.built = true;
  }

  // Gathers cell k's local values of a global vector.
  void gather(unsigned int k, const Vector<double>& global, std::vector<double>& local) const {
    for (unsigned int i = 0; i < cache.n; ++i) local[i] = global[cache.indices[std::size_t(k) * cache.n + i]];
  }

  // F = I + grad u at quadrature point q of cell k, from the cell's local displacements.
  Tensor2 deformation_gradient(unsigned int k, unsigned int q, const std::vector<double>& u_local) const {
    const Cache& c = cache;
    const Tensor<1, 3>* grad = &c.gradients[(std::size_t(k) * c.nq + q) * c.nbase];
    Tensor2 F;
    for (unsigned int i = 0; i < c.n; ++i)
      for (int J = 0; J < 3; ++J) F[c.component[i]][J] += u_local[i] * grad[c.base[i]][J];
    for (int d = 0; d < 3; ++d) F[d][d] += 1;
    return F;
  }

  // Where each cell matrix entry (i, j) goes in the tangent's value array; -1 where the row or the
  // column is constrained. Built once per set of supports.
  std::vector<int> scatter;
  void build_scatter() {
    const unsigned int n = cache.n, cells = tria.n_active_cells();
    scatter.resize(std::size_t(cells) * n * n);
    for (unsigned int k = 0; k < cells; ++k) {
      const types::global_dof_index* indices = &cache.indices[std::size_t(k) * n];
      int* out = &scatter[std::size_t(k) * n * n];
      for (unsigned int i = 0; i < n; ++i)
        for (unsigned int j = 0; j < n; ++j)
          out[i * n + j] = constrained[indices[i]] || constrained[indices[j]]
                               ? -1
                               : tangent.position(static_cast<int>(indices[i]), static_cast<int>(indices[j]));
    }
  }

  // One thread's share of the assembly: cells [begin, end) add -f_int into r, f_int into `internal`
  // (if given) and, if `values`, the tangent into that value array. False if J <= 0 somewhere.
  bool assemble_cells(unsigned int begin, unsigned int end, const Vector<double>& inertial, double* r, double* internal,
                      double* values) const {  // my_cells[begin, end)
    const Cache& c = cache;
    const bool tangent = values != nullptr;
    const unsigned int n = c.n, nq = c.nq;
    std::vector<double> inertial_local(dynamic ? n : 0);
    FullMatrix<double> cell_matrix(n, n);
    Vector<double> cell_internal(n);
    std::vector<double> u_local(n);
    std::vector<std::array<Tensor<1, 3>, 3>> a_grad(n);
    std::vector<double> volume_gradient(mean_dilatation ? n : 0);
    std::vector<Tensor2> F_at(nq);  // per quadrature point of the cell
    Tensor2 P;
    Tensor4 A;
    for (unsigned int kk = begin; kk < end; ++kk) {
      const unsigned int k = my_cells[kk];
      const types::global_dof_index* indices = &c.indices[std::size_t(k) * n];
      const Material& material = *cell_material[k];
      gather(k, u, u_local);
      for (unsigned int q = 0; q < nq; ++q) F_at[q] = deformation_gradient(k, q, u_local);
      cell_matrix = 0;
      cell_internal = 0;
      // Mean dilatation: U(J) becomes U(theta) of the cell's volume ratio theta = v / V, its
      // pressure p = U'(theta) constant over the cell (the displacement-pressure formulation with a
      // pressure constant per cell, condensed).
      double reference_volume = 0, pressure = 0, pressure_stiffness = 0;
      if (mean_dilatation) {
        double volume = 0;
        for (unsigned int q = 0; q < nq; ++q) {
          const double jxw = c.jxw[std::size_t(k) * nq + q];
          const double j = determinant(F_at[q]);
          if (!(j > 0)) return false;
          volume += j * jxw;
          reference_volume += jxw;
        }
        material.volumetric(volume / reference_volume, pressure, pressure_stiffness);
        std::fill(volume_gradient.begin(), volume_gradient.end(), 0.0);
      }
      for (unsigned int q = 0; q < nq; ++q) {
        const Tensor<1, 3>* grad = &c.gradients[(std::size_t(k) * nq + q) * c.nbase];
        const double jxw = c.jxw[std::size_t(k) * nq + q];
        const Tensor2& F = F_at[q];
        if (!material.evaluate(F, P, tangent ? &A : nullptr)) return false;
        if (mean_dilatation) {
          // Swap the point's volumetric stress U'(J) J F^-T for the cell's p J F^-T, and in the
          // tangent U''(J) J^2 F^-T x F^-T + U'(J) d2J for p d2J, d2J = J (F^-T x F^-T - F^-T o F^-1).
          const double j = determinant(F);
          const Tensor2 f_inv_t = transpose(invert(F));
          double u1 = 0, u2 = 0;
          material.volumetric(j, u1, u2);
          const double excess = u1 - pressure;
          P -= excess * j * f_inv_t;
          if (tangent)
            for (int a = 0; a < 3; ++a)
              for (int b = 0; b < 3; ++b)
                for (int cc = 0; cc < 3; ++cc)
                  for (int d = 0; d < 3; ++d)
                    A[a][b][cc][d] -= u2 * j * j * f_inv_t[a][b] * f_inv_t[cc][d] +
                                      excess * j * (f_inv_t[a][b] * f_inv_t[cc][d] - f_inv_t[a][d] * f_inv_t[cc][b]);
          for (unsigned int i = 0; i < n; ++i)  // dv/du_i = int J F^-T : grad N_i
            volume_gradient[i] += j * (f_inv_t[c.component[i]] * grad[c.base[i]]) * jxw;
        }
        if (tangent)  // a_grad[j][c] = A[c][.][c_j][.] grad phi_j, so that K_ij = grad phi_i . a_grad[j][c_i]
          for (unsigned int j = 0; j < n; ++j) {
            const Tensor<1, 3>& g = grad[c.base[j]];
            for (int ci = 0; ci < 3; ++ci)
              for (int J = 0; J < 3; ++J) {
                double v = 0;
                for (int L = 0; L < 3; ++L) v += A[ci][J][c.component[j]][L] * g[L];
                a_grad[j][ci][J] = v * jxw;
              }
          }
        for (unsigned int i = 0; i < n; ++i) {
          const unsigned int ci = c.component[i];
          const Tensor<1, 3>& g = grad[c.base[i]];
          cell_internal(i) += (P[ci][0] * g[0] + P[ci][1] * g[1] + P[ci][2] * g[2]) * jxw;
          if (!tangent) continue;
          for (unsigned int j = 0; j < n; ++j) cell_matrix(i, j) += g * a_grad[j][ci];
        }
      }
      if (mean_dilatation && tangent) {  // U''(theta)/V (dv/du)(dv/du)'
        const double scale = pressure_stiffness / reference_volume;
        for (unsigned int i = 0; i < n; ++i)
          for (unsigned int j = 0; j < n; ++j) cell_matrix(i, j) += scale * volume_gradient[i] * volume_gradient[j];
      }
      if (dynamic) {
        // M (a+ + alpha v+) with the consistent mass, and its derivative in the tangent.
        const double rho = dynamics.density_kg_per_m3, gain = inertia_gain();
        gather(k, inertial, inertial_local);
        for (unsigned int q = 0; q < nq; ++q) {
          const double* shape = &c.shape_values[q * c.nbase];
          const double w = rho * c.jxw[std::size_t(k) * nq + q];
          double field[3] = {0, 0, 0};
          for (unsigned int j = 0; j < n; ++j) field[c.component[j]] += shape[c.base[j]] * inertial_local[j];
          for (unsigned int i = 0; i < n; ++i) {
            cell_internal(i) += w * shape[c.base[i]] * field[c.component[i]];
            if (!tangent) continue;
            for (unsigned int j = 0; j < n; ++j)
              if (c.component[j] == c.component[i]) cell_matrix(i, j) += gain * w * shape[c.base[i]] * shape[c.base[j]];
          }
        }
      }
      // Homogeneous constraints: constrained rows and columns are dropped (finish() puts their diagonal).
      const int* where = tangent ? &scatter[std::size_t(k) * n * n] : nullptr;
      for (unsigned int i = 0; i < n; ++i) {
        if (internal) internal[indices[i]] += cell_internal(i);
        if (!constrained[indices[i]]) r[indices[i]] -= cell_internal(i);
        if (!tangent) continue;
        for (unsigned int j = 0; j < n; ++j)
          if (where[i * n + j] >= 0) values[where[i * n + j]] += cell_matrix(i, j);
      }
    }
    return true;
  }

  // Two threads (the machine has 2 cores; the haptic thread sleeps between its microsecond ticks)
  // assemble halves of the cells, the second into its own buffers, which are then added.
  struct ThreadBuffers {
    std::vector<double> r, internal, values;
  } second;
  static constexpr unsigned int kCellsPerThread = 1000;  // fewer: one thread

  bool assemble_impl(double lambda, Vector<double>& r, bool tangent, Vector<double>* internal) {
    if (!cache.built) build_cache();
    const Cache& c = cache;
    if (tangent && scatter.size() != std::size_t(tria.n_active_cells()) * c.n * c.n) build_scatter();
    // With inertia: v+ and a+ + alpha v+ at every dof, once per assembly (not once per cell sharing it).
    Vector<double> inertial, velocities;
    if (dynamic) {
      inertial.reinit(u.size());
      velocities.reinit(u.size());
      for (types::global_dof_index i = 0; i < u.size(); ++i) {
        const double a_new = acceleration(u[i], i);
        velocities[i] = velocity(u[i], a_new, i);
        inertial[i] = a_new + dynamics.rayleigh_mass_per_s * velocities[i];
      }
    }
    r = 0;
    if (internal) *internal = 0;
    if (tangent) {
      this->tangent.zero();
      tangent_current = false;
    }
    const unsigned int cells = static_cast<unsigned int>(my_cells.size());
    double* values = tangent ? this->tangent.values() : nullptr;
    bool ok = true;
    if (cells < 2 * kCellsPerThread || ranks > 1) {  // in parallel the ranks take the cores
      ok = assemble_cells(0, cells, inertial, r.begin(), internal ? internal->begin() : nullptr, values);
    } else {
      const unsigned int half = cells / 2;
      const std::size_t dofs = u.size();
      second.r.assign(dofs, 0.0);
      if (internal) second.internal.assign(dofs, 0.0);
      if (tangent) second.values.assign(this->tangent.nonzeros(), 0.0);
      bool second_ok = true;
      std::thread worker([&] {
        second_ok = assemble_cells(half, cells, inertial, second.r.data(), internal ? second.internal.data() : nullptr,
                                   tangent ? second.values.data() : nullptr);
      });
      const bool first_ok = assemble_cells(0, half, inertial, r.begin(), internal ? internal->begin() : nullptr, values);
      worker.join();
      ok = first_ok && second_ok;
      for (std::size_t i = 0; ok && i < dofs; ++i) r[i] += second.r[i];
      if (internal && ok)
        for (std::size_t i = 0; i < dofs; ++i) (*internal)[i] += second.internal[i];
      if (tangent && ok)
        for (std::size_t i = 0; i < second.values.size(); ++i) values[i] += second.values[i];
    }
    // Every rank must take the same decision, then hold the same sums.
    if (!all_ranks(ok)) return false;
    sum_over_ranks(r.begin(), r.size());
    if (internal) sum_over_ranks(internal->begin(), internal->size());
    if (tangent) sum_over_ranks(values, this->tangent.nonzeros());
    if (dynamic && dynamics.rayleigh_stiffness_s != 0 && !reference_stiffness.empty()) {
      // beta K0 v+ into the residual, beta K0 dv+/du+ into the tangent.
      Vector<double> damping(u.size());
      this->tangent.multiply(reference_stiffness.data(), velocities.begin(), damping.begin());
      const double beta = dynamics.rayleigh_stiffness_s, gain = beta * velocity_gain();
      for (types::global_dof_index i = 0; i < u.size(); ++i) {
        if (internal) (*internal)[i] += beta * damping[i];
        if (!constrained[i]) r[i] -= beta * damping[i];
      }
      if (tangent)
        for (std::size_t k = 0; k < reference_stiffness.size(); ++k) values[k] += gain * reference_stiffness[k];
    }
    if (cavity.active && !assemble_cavity(r, tangent, internal)) return false;
    if (tangent) {
      this->tangent.finish(constrained);
      tangent_current = true;
    }
    r.add(static_factor(lambda), c.external);
    if (internal) internal->add(-static_factor(lambda), c.external);
    for (const Patch& p : patches)
      for (int comp = 0; comp < 3; ++comp) {
        const double f = p.converged_force[comp] + lambda * (p.force[comp] - p.converged_force[comp]);
        if (f == 0) continue;
        r.add(f, p.h[comp]);
        if (internal) internal->add(-f, p.h[comp]);
      }
    constraints.set_zero(r);
    return true;
  }

  // Calls visit(cell, face_values, q, w, first) at every boundary quadrature point within a patch's
  // radius: w = (1 - (d/r)^2)^2 JxW is the unnormalised kernel weight, `first` marks the first
  // point visited on a face (to evaluate per-face data once); face_values carries `flags`.
  template <class Visit>
  void for_each_patch_point(const Patch& p, UpdateFlags flags, Visit visit) const {
    FEFaceValues<3> face_values(*mapping, *fe, *face_quadrature, flags | update_JxW_values | update_quadrature_points);
    for (const auto& cell : dof.active_cell_iterators())
      for (const unsigned int f : cell->face_indices()) {
        if (!cell->face(f)->at_boundary()) continue;
        // Skip faces that are entirely out of reach (a cheap bound through the face's diameter).
        if (cell->face(f)->center().distance(p.center) > p.radius + cell->face(f)->diameter()) continue;
        face_values.reinit(cell, f);
        bool first = true;
        for (unsigned int q = 0; q < face_quadrature->size(); ++q) {
          const double d = face_values.quadrature_point(q).distance(p.center) / p.radius;
          if (d >= 1) continue;
          visit(cell, face_values, q, (1 - d * d) * (1 - d * d) * face_values.JxW(q), first);
          first = false;
        }
      }
  }

  void build_patch(Patch& p) {
    const unsigned int n = fe->n_dofs_per_cell();
    std::vector<types::global_dof_index> indices(n);
    for (Vector<double>& row : p.h) row.reinit(dof.n_dofs());
    double total = 0;
    for_each_patch_point(p, update_values,
                         [&](const auto& cell, const FEFaceValues<3>& values, unsigned int q, double w, bool first) {
      total += w;
      if (first) cell->get_dof_indices(indices);
      for (unsigned int i = 0; i < n; ++i) {
        const unsigned int c = fe->system_to_component_index(i).first;
        p.h[c][indices[i]] += w * values.shape_value_component(i, q, c);
      }
    });
    if (!(total > 0))
      throw std::invalid_argument("contact patch: no boundary surface within the radius of its centre");
    for (Vector<double>& row : p.h) row /= total;
  }

  // Adds a linear solve's figures to the running solve's.
  void account(const TangentSystem::SolveStats& stats) {
    factorisation_s += stats.factor_s;
    solve_s += stats.solve_s;
    linear_iterations += stats.iterations;
  }

  // x = K^-1 rhs to a relative residual `tolerance`, x holding the initial guess unless zero_guess.
  void solve_tangent(const Vector<double>& rhs, Vector<double>& x, double tolerance, bool zero_guess) {
    x.reinit(rhs.size(), /*omit_zeroing_entries=*/!zero_guess);
    account(tangent.solve(rhs.begin(), x.begin(), tolerance, zero_guess));
    if (cavity.active && cavity.stiffness != 0) {
      // Sherman-Morrison: (K_s + c g g')^-1 b = x - c (g.x) / (1 + c g.y) y, x = K_s^-1 b, y = K_s^-1 g.
      if (!cavity.y_current) {
        account(tangent.solve(cavity.g.begin(), cavity.y.begin(), std::min(tolerance, 1e-10), /*zero_guess=*/false));
        cavity.y_current = true;
      }
      const double c = cavity.stiffness;
      x.add(-c * (cavity.g * x) / (1 + c * (cavity.g * cavity.y)), cavity.y);
    }
    constraints.distribute(x);
  }

  // `reference`: the residual norm the tolerance is relative to; negative: the first iteration's.
  StepReport newton(double lambda, const NewtonSettings& s, double reference = -1) {
    StepReport report;
    report.load_factor = lambda;
    apply_prescribed(lambda);
    Vector<double> r(dof.n_dofs()), du, trial_r(dof.n_dofs());
    bool assembled = false;  // r and the tangent are already those of the current u
    for (int it = 0; it <= s.max_iterations; ++it) {
      if (!assembled && !assemble(lambda, r, /*tangent=*/true)) {
        report.failure = "an element inverted (J <= 0)";
        return report;
      }
      assembled = false;
      const double norm = r.l2_norm();
      report.residuals.push_back(norm);
      if (!std::isfinite(norm)) {
        report.failure = "the residual is not finite";
        return report;
      }
      if (reference < 0) reference = norm;
      const bool volume_ok = !cavity.active || std::abs(cavity.volume_residual) <= 1e-10 * cavity.reference_volume;
      if (volume_ok && (norm <= s.relative_tolerance * reference || norm <= s.absolute_tolerance)) {
        report.converged = true;
        report.iterations = it;
        return report;
      }
      if (it == s.max_iterations) break;
      // Inexact Newton: the step solves the tangent to a tolerance that shrinks with the residual
      // (superlinear convergence; quadratic in the limit).
      // Far from the solution 1e-3; once the residual has dropped a hundredfold (the quadratic regime),
      // aim the step straight at the convergence tolerance.
      const double eta = norm < 5e-2 * reference ? 0.5 * s.relative_tolerance * reference / norm : 1e-3;
      solve_tangent(r, du, std::clamp(eta, 1e-12, 1e-3), /*zero_guess=*/true);
      // With a cavity, the pressure's step: K_s du - g dp = r, g'du - V_law'(p) dp = -(V - V_law),
      // i.e. du = x + y dp, dp = -(r_V + g'x) / (g'y + 1/c); solve_tangent gave x + y dp for r_V = 0.
      double dp = 0;
      if (cavity.active) {
        const double c = cavity.stiffness, gy = cavity.g * cavity.y;
        const double gx = (cavity.g * du) * (1 + c * gy);  // g'x from g'(x + y dp0) = g'x / (1 + c g'y)
        dp = -(cavity.volume_residual + gx) / (gy + 1 / c);
        du.add(-cavity.volume_residual / (gy + 1 / c), cavity.y);
        constraints.distribute(du);
      }
      const double pressure_start = cavity.pressure;
      // Backtracking: halve until the residual decreases and no element inverts. The full step is
      // assembled with its tangent, which the next iteration then reuses (one assembly per Newton
      // iteration when the full step is taken, as it is near convergence).
      const Vector<double> start = u;
      double alpha = 1;
      bool accepted = false;
      for (int b = 0; b < 10 && !accepted; ++b, alpha /= 2) {
        u = start;
        u.add(alpha, du);
        cavity.pressure = pressure_start + alpha * dp;
        const bool full = b == 0;
        if (!assemble(lambda, trial_r, /*tangent=*/full)) continue;
        accepted = trial_r.l2_norm() < (1 - 1e-4 * alpha) * norm || b == 9;
        if (accepted && full) {
          r.swap(trial_r);
          assembled = true;
        }
      }
      if (!accepted) {
        u = start;
        cavity.pressure = pressure_start;
        report.failure = "the line search found no admissible step";
        return report;
      }
    }
    report.iterations = s.max_iterations;
    report.failure = "no convergence in " + std::to_string(s.max_iterations) + " Newton iterations";
    return report;
  }
};

QuasiStaticSolver::QuasiStaticSolver(const Triangulation<3>& triangulation, const Material& material, int degree,
                                     MPI_Comm comm)
    : impl_(std::make_unique<Impl>(triangulation, material, degree, comm)) {}

void QuasiStaticSolver::use_algebraic_multigrid(bool on) {
  impl_->linear_method = on ? TangentSystem::Method::amg : TangentSystem::Method::factorisation;
  impl_->set_up = false;
}

int QuasiStaticSolver::ranks() const { return impl_->ranks; }

QuasiStaticSolver::~QuasiStaticSolver() = default;
QuasiStaticSolver::QuasiStaticSolver(QuasiStaticSolver&&) noexcept = default;
QuasiStaticSolver& QuasiStaticSolver::operator=(QuasiStaticSolver&&) noexcept = default;

void QuasiStaticSolver::prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                                               const Tensor<1, 3>& value) {
  impl_->prescribed.push_back({boundary_id, components, [value](const Point<3>&) { return value; }});
  impl_->set_up = false;
}

void QuasiStaticSolver::prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                                               std::function<Tensor<1, 3>(const Point<3>&)> field) {
  impl_->prescribed.push_back({boundary_id, components, std::move(field)});
  impl_->set_up = false;
}

void QuasiStaticSolver::apply_traction(unsigned int boundary_id, const Tensor<1, 3>& traction) {
  impl_->tractions.push_back({boundary_id, traction});
  impl_->cache.built = false;
}

unsigned int QuasiStaticSolver::dofs() const { return impl_->dof.n_dofs(); }

unsigned int QuasiStaticSolver::cells() const { return impl_->tria.n_active_cells(); }

QuasiStaticSolver::CellFields QuasiStaticSolver::cell_fields() const {
  Impl& m = *impl_;
  if (!m.cache.built) m.build_cache();
  const unsigned int cells = m.tria.n_active_cells(), nq = m.cache.nq;
  CellFields fields;
  fields.jacobian.reserve(cells);
  fields.von_mises.reserve(cells);
  std::vector<double> u_local(m.cache.n);
  for (unsigned int k = 0; k < cells; ++k) {
    m.gather(k, m.u, u_local);
    double j_sum = 0, vm_sum = 0;
    for (unsigned int q = 0; q < nq; ++q) {
      const Tensor2 F = m.deformation_gradient(k, q, u_local);
      const double j = determinant(F);
      j_sum += j;
      Tensor2 P;
      if (j > 0 && m.cell_material[k]->evaluate(F, P, nullptr)) {
        const Tensor<2, 3> sigma = P * transpose(F) / j;  // Cauchy
        const Tensor<2, 3> dev = sigma - trace(sigma) / 3 * unit_symmetric_tensor<3>();
        vm_sum += std::sqrt(1.5 * scalar_product(dev, dev));
      }
    }
    fields.jacobian.push_back(j_sum / nq);
    fields.von_mises.push_back(vm_sum / nq);
  }
  return fields;
}

double QuasiStaticSolver::max_displacement() const {
  const Impl& m = *impl_;
  std::vector<types::global_dof_index> indices(m.fe->n_dofs_per_cell());
  double worst = 0;
  for (const auto& cell : m.dof.active_cell_iterators()) {
    cell->get_dof_indices(indices);
    for (unsigned int node = 0; node < m.fe->base_element(0).n_dofs_per_cell(); ++node) {
      Tensor<1, 3> u;
      for (unsigned int c = 0; c < 3; ++c) u[c] = m.u[indices[m.fe->component_to_system_index(c, node)]];
      worst = std::max(worst, u.norm());
    }
  }
  return worst;
}

// The deformed state as DataOut patches: displacement (dof data), J and von Mises stress (cell data),
// optionally on the cells of one rank only.
struct QuasiStaticSolver::Output {
  DataOut<3> out;
  Vector<double> jacobian, von_mises;
};

void QuasiStaticSolver::write_vtu(const std::string& path) const {
  Output o;
  fill_output(o, false);
  std::ofstream file(path);
  if (!file) throw std::runtime_error("cannot write " + path);
  o.out.write_vtu(file);
  if (!file) throw std::runtime_error("cannot write " + path);
}

std::string QuasiStaticSolver::write_vtu_pieces(const std::string& directory, const std::string& name,
                                                unsigned int counter) const {
  Output o;
  fill_output(o, true);
  try {
    return o.out.write_vtu_with_pvtu_record(directory + "/", name, counter, impl_->comm, 4);
  } catch (const std::exception&) {
    throw std::runtime_error("cannot write " + directory + "/" + name + " (parallel VTU pieces)");
  }
}

void QuasiStaticSolver::fill_output(Output& o, bool own_cells_only) const {
  const Impl& m = *impl_;
  o.out.attach_dof_handler(m.dof);
  const std::vector<std::string> names(3, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> kinds(
      3, DataComponentInterpretation::component_is_part_of_vector);
  o.out.add_data_vector(m.u, names, DataOut<3>::type_dof_data, kinds);
  const CellFields fields = cell_fields();
  o.jacobian = Vector<double>(fields.jacobian.begin(), fields.jacobian.end());
  o.von_mises = Vector<double>(fields.von_mises.begin(), fields.von_mises.end());
  o.out.add_data_vector(o.jacobian, "J", DataOut<3>::type_cell_data);
  o.out.add_data_vector(o.von_mises, "von_mises_stress_pa", DataOut<3>::type_cell_data);
  if (own_cells_only)
    o.out.set_cell_selection([&m](const typename Triangulation<3>::cell_iterator& cell) {
      return cell->is_active() && m.cell_rank[cell->active_cell_index()] == static_cast<unsigned int>(m.rank);
    });
  o.out.build_patches(*m.mapping, m.fe->degree);
}

int QuasiStaticSolver::add_contact_patch(const Point<3>& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("contact patch: the radius must be positive");
  Impl::Patch patch{center, radius, {}, Tensor<1, 3>(), Tensor<1, 3>()};
  impl_->build_patch(patch);
  impl_->patches.push_back(std::move(patch));
  return static_cast<int>(impl_->patches.size()) - 1;
}

void QuasiStaticSolver::set_patch_force(int patch, const Tensor<1, 3>& force) { impl_->patches.at(patch).force = force; }

void QuasiStaticSolver::move_contact_patch(int patch, const Point<3>& center) {
  Impl::Patch& p = impl_->patches.at(patch);
  Impl::Patch moved{center, p.radius, {}, p.force, p.converged_force};
  impl_->build_patch(moved);
  p = std::move(moved);
}

namespace {

// The point of triangle abc nearest p, as barycentric weights of a, b, c (Ericson, Real-Time
// Collision Detection, 5.1.5: by the Voronoi regions of the triangle's vertices and edges).
std::array<double, 3> nearest_on_triangle(const Point<3>& p, const Point<3>& a, const Point<3>& b, const Point<3>& c) {
  const Tensor<1, 3> ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Tensor<1, 3> bp = p - b;
  const double d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Tensor<1, 3> cp = p - c;
  const double d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denominator = 1 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return {1 - v - w, v, w};
}

}  // namespace

Point<3> QuasiStaticSolver::boundary_point_nearest(const Point<3>& x, bool deformed_surface) const {
  const Impl& m = *impl_;
  double best = std::numeric_limits<double>::infinity();
  Point<3> answer = x;
  std::vector<Point<3>> reference, deformed;
  const bool displaced = deformed_surface && m.u.size() == m.dof.n_dofs();  // none before the first solve
  for (const auto& cell : m.dof.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const auto face = cell->face(f);
      reference.clear(), deformed.clear();
      for (const unsigned int k : face->vertex_indices()) {
        reference.push_back(face->vertex(k));
        Point<3> y = face->vertex(k);
        if (displaced)
          for (unsigned int c = 0; c < 3; ++c) y[c] += m.u[face->vertex_dof_index(k, c)];
        deformed.push_back(y);
      }
      // A quadrilateral's vertices are in lexicographic order (0 1 / 2 3): triangles 0 1 3, 0 3 2.
      static const std::array<std::array<int, 3>, 2> quad{{{0, 1, 3}, {0, 3, 2}}}, triangle{{{0, 1, 2}, {0, 1, 2}}};
      const auto& triangles = reference.size() == 4 ? quad : triangle;
      for (const auto& t : triangles) {
        const auto w = nearest_on_triangle(x, deformed[t[0]], deformed[t[1]], deformed[t[2]]);
        Point<3> y, X;
        for (int i = 0; i < 3; ++i) {
          y += w[i] * Tensor<1, 3>(deformed[t[i]]);
          X += w[i] * Tensor<1, 3>(reference[t[i]]);
        }
        const double d = y.distance_square(x);
        if (d < best) best = d, answer = X;
      }
    }
  return answer;
}

Tensor<1, 3> QuasiStaticSolver::patch_displacement(int patch) const {
  const auto& p = impl_->patches.at(patch);
  Tensor<1, 3> d;
  for (int c = 0; c < 3; ++c) d[c] = p.h[c] * impl_->u;
  return d;
}

const ComplianceTimes& QuasiStaticSolver::last_compliance_times() const { return impl_->compliance_times; }

Point<3> QuasiStaticSolver::patch_center(int patch) const { return impl_->patches.at(patch).center; }

int QuasiStaticSolver::patches() const { return static_cast<int>(impl_->patches.size()); }

double QuasiStaticSolver::patch_radius(int patch) const { return impl_->patches.at(patch).radius; }

Tensor<1, 3> QuasiStaticSolver::patch_normal(int patch) const {
  const Impl& m = *impl_;
  const auto& p = m.patches.at(patch);
  const FEValuesExtractors::Vector displacement(0);
  std::vector<Tensor<2, 3>> grad_u(m.face_quadrature->size());
  Tensor<1, 3> sum;
  m.for_each_patch_point(p, update_gradients | update_normal_vectors,
                         [&](const auto&, const FEFaceValues<3>& values, unsigned int q, double w, bool first) {
                           if (first) values[displacement].get_function_gradients(m.u, grad_u);
                           Tensor<2, 3> F = grad_u[q];
                           for (int i = 0; i < 3; ++i) F[i][i] += 1;
                           sum += w * (determinant(F) * transpose(invert(F)) * values.normal_vector(q));
                         });
  return sum / sum.norm();
}

FullMatrix<double> QuasiStaticSolver::compliance() {
  Impl& m = *impl_;
  m.setup_constraints();
  m.factorisation_s = m.solve_s = 0;
  m.linear_iterations = 0;
  const int factorisations = m.tangent.factorisations();
  auto start = std::chrono::steady_clock::now();
  if (!m.tangent_current) {  // after a converged solve the tangent already is the current state's
    Vector<double> r(m.dof.n_dofs());
    if (!m.assemble(1.0, r, /*tangent=*/true)) throw std::runtime_error("compliance: an element is inverted");
  }
  m.compliance_times = ComplianceTimes();
  m.compliance_times.assembly_s = Impl::since(start);
  const unsigned int columns = 3 * m.patches.size();
  const auto h = [&](unsigned int k) {
    Vector<double> column = m.patches[k / 3].h[k % 3];
    m.constraints.set_zero(column);
    return column;
  };
  std::vector<Vector<double>>& z = m.compliance_columns;
  FullMatrix<double> w(columns, columns);
  // The last compliance's columns span the answer almost exactly when the state moved little: the
  // Galerkin solution in their span, z = Z C with (Z'K Z) C = Z'H', costs 3m products with K and
  // no solve. Its residual R = H' - K Z C bounds the error of W = H Z C (which is R'K^-1 R, quadratic
  // in R). While R exceeds kGalerkinTolerance, the span grows by the preconditioned residuals P^-1 R
  // (one blocked application of the factorisation, which reduces R as a CG step would) and the
  // Galerkin solution is taken again; a first compliance, or one that does not get there in three
  // rounds, solves each column to kComplianceTolerance.
  const types::global_dof_index n = m.dof.n_dofs();
  bool solve_columns = z.size() != columns;
  double worst = std::numeric_limits<double>::infinity();
  std::vector<Vector<double>> basis = z;
  for (int round = 0; !solve_columns; ++round) {
    const unsigned int size = basis.size();
    std::vector<Vector<double>> kb(size, Vector<double>(n));
    for (unsigned int k = 0; k < size; ++k) m.multiply(basis[k], kb[k]);
    FullMatrix<double> galerkin(size, size), hb(columns, size);
    for (unsigned int a = 0; a < size; ++a)
      for (unsigned int b = 0; b < size; ++b) galerkin(a, b) = basis[a] * kb[b];
    for (unsigned int a = 0; a < columns; ++a)
      for (unsigned int b = 0; b < size; ++b) hb(a, b) = h(a) * basis[b];
    galerkin.gauss_jordan();  // (B'K B)^-1
    FullMatrix<double> c(size, columns);
    galerkin.mTmult(c, hb);   // C = (B'K B)^-1 (H B)'
    std::vector<double> residuals(std::size_t(n) * columns);  // column-major, for the blocked solve
    worst = 0;
    for (unsigned int k = 0; k < columns; ++k) {
      z[k] = 0;
      Vector<double> residual = h(k);
      const double scale = residual.l2_norm();
      for (unsigned int j = 0; j < size; ++j) {
        z[k].add(c(j, k), basis[j]);
        residual.add(-c(j, k), kb[j]);
      }
      worst = std::max(worst, residual.l2_norm() / scale);
      std::copy(residual.begin(), residual.end(), residuals.begin() + std::size_t(k) * n);
    }
    if (worst <= kGalerkinTolerance) break;
    if (!std::isfinite(worst) || round == 3) {
      solve_columns = true;
      break;
    }
    std::vector<double> corrections(residuals.size());
    TangentSystem::SolveStats stats = m.tangent.apply_factorisation(residuals.data(), corrections.data(), columns);
    stats.iterations = 1;  // one blocked application
    m.account(stats);
    basis = z;
    for (unsigned int k = 0; k < columns; ++k) {
      Vector<double> d(n);
      std::copy_n(corrections.begin() + std::size_t(k) * n, n, d.begin());
      m.constraints.distribute(d);
      basis.push_back(std::move(d));
    }
  }
  m.compliance_times.galerkin_residual = std::isfinite(worst) ? worst : 0;
  const bool refine = solve_columns;
  if (solve_columns) {
    const bool warm = z.size() == columns;
    if (!warm) z.assign(columns, Vector<double>(n));
    for (unsigned int k = 0; k < columns; ++k) m.solve_tangent(h(k), z[k], kComplianceTolerance, /*zero_guess=*/!warm);
  }
  m.compliance_times.refined = refine;
  m.compliance_times.factorisation_s = m.factorisation_s;
  m.compliance_times.solves_s = m.solve_s;
  m.compliance_times.linear_iterations = m.linear_iterations;
  m.compliance_times.factorisations = m.tangent.factorisations() - factorisations;
  for (unsigned int a = 0; a < columns; ++a)
    for (unsigned int b = 0; b < columns; ++b) w(a, b) = h(a) * z[b];
  // W is symmetric; the solves leave an asymmetry of the order of their tolerance.
  for (unsigned int a = 0; a < columns; ++a)
    for (unsigned int b = 0; b < a; ++b) w(a, b) = w(b, a) = (w(a, b) + w(b, a)) / 2;
  return w;
}

void QuasiStaticSolver::add_cavity(unsigned int boundary_id, const CavityLaw& law) {
  Impl& m = *impl_;
  if (m.cavity.active) throw std::invalid_argument("cavity: only one cavity per body");
  if (m.fe->degree != 1)
    throw std::invalid_argument("cavity: the wall is taken as flat faces between vertices; use P1 or Q1 elements");
  if (law.gas ? !(law.initial_pressure_pa > 0) : !(law.bulk_modulus_pa > 0))
    throw std::invalid_argument("cavity: a gas needs a positive initial pressure, a liquid a positive bulk modulus");
  m.cavity.boundary = boundary_id;
  m.cavity.law = law;
  m.build_cavity_wall();
  m.cavity.pressure = law.initial_pressure_pa;
  m.cavity.active = true;
}

double QuasiStaticSolver::cavity_volume() const {
  const Impl& m = *impl_;
  return m.cavity.active ? m.cavity.wall.volume(m.u.begin()) : 0.0;
}

double QuasiStaticSolver::cavity_reference_volume() const { return impl_->cavity.reference_volume; }

double QuasiStaticSolver::cavity_pressure() const {
  const Impl& m = *impl_;
  return m.cavity.active ? m.cavity.pressure : 0.0;
}

namespace {

void require_decoupled(const Material& material) {
  double u1 = 0, u2 = 0;
  if (!material.volumetric(1.0, u1, u2))
    throw std::invalid_argument("the mean-dilatation formulation needs a decoupled material (neo_hookean_incompressible "
                                "or mooney_rivlin), not " + material.name());
}

}  // namespace

void QuasiStaticSolver::set_region_material(unsigned int material_id, const Material& material) {
  Impl& m = *impl_;
  if (m.mean_dilatation) require_decoupled(material);
  m.region_materials[static_cast<types::material_id>(material_id)] = &material;
  m.cache.built = false;
}

void QuasiStaticSolver::use_mean_dilatation(bool on) {
  if (on) {
    require_decoupled(impl_->material);
    for (const auto& [id, material] : impl_->region_materials) require_decoupled(*material);
  }
  impl_->mean_dilatation = on;
}

void QuasiStaticSolver::enable_dynamics(const Dynamics& dynamics) {
  if (!(dynamics.time_step_s > 0) || !(dynamics.density_kg_per_m3 > 0))
    throw std::invalid_argument("dynamics: the time step and the density must be positive");
  if (dynamics.rayleigh_mass_per_s < 0 || dynamics.rayleigh_stiffness_s < 0)
    throw std::invalid_argument("dynamics: Rayleigh damping coefficients must not be negative");
  Impl& m = *impl_;
  m.dynamic = true;
  m.dynamics = dynamics;
  m.step_constants();
  m.v_old.reinit(m.u.size());
  m.a_old.reinit(m.u.size());
}

void QuasiStaticSolver::apply_body_force(std::function<Tensor<1, 3>(const Point<3>&)> force) {
  impl_->body_force = std::move(force);
  impl_->cache.built = false;
}

double QuasiStaticSolver::l2_error(const std::function<Tensor<1, 3>(const Point<3>&)>& exact) const {
  const Impl::ScaledField field(exact, 1.0);
  Vector<float> per_cell(impl_->tria.n_active_cells());
  const unsigned int order = impl_->fe->degree + 2;
  std::unique_ptr<Quadrature<3>> q;
  if (impl_->simplex)
    q = std::make_unique<QGaussSimplex<3>>(order);
  else
    q = std::make_unique<QGauss<3>>(order);
  VectorTools::integrate_difference(*impl_->mapping, impl_->dof, impl_->u, field, per_cell, *q, VectorTools::L2_norm);
  return VectorTools::compute_global_error(impl_->tria, per_cell, VectorTools::L2_norm);
}

SolveReport QuasiStaticSolver::solve(const NewtonSettings& s) {
  Impl& m = *impl_;
  m.setup_constraints();
  if (m.dynamic && m.dynamics.rayleigh_stiffness_s != 0 && m.reference_stiffness.empty())
    m.build_reference_stiffness();
  const Vector<double> initial = m.u;
  const double initial_pressure = m.cavity.pressure;
  if (m.dynamic) m.u_old = initial;
  m.assembly_s = m.factorisation_s = m.solve_s = 0;
  m.linear_iterations = 0;
  const int factorisations = m.tangent.factorisations();
  SolveReport report;
  const auto times = [&] {
    report.assembly_s = m.assembly_s, report.factorisation_s = m.factorisation_s, report.solve_s = m.solve_s;
    report.linear_iterations = m.linear_iterations;
    report.factorisations = m.tangent.factorisations() - factorisations;
  };
  double done = 0, increment = 1.0 / std::max(1, s.load_steps);
  // A frame that changes only the patch forces starts from the linear prediction u + Z dF, Z = K^-1 H'
  // the last compliance's columns (at this state): a Newton step without assembly or solve. The
  // tolerance stays relative to the residual the force change makes at the old state, |H' dF|.
  bool predict = !m.dynamic && m.static_done == 1 && s.load_steps <= 1 && !m.patches.empty() &&
                 m.compliance_columns.size() == 3 * m.patches.size();
  while (done < 1 - 1e-12) {
    const double target = std::min(1.0, done + increment);
    const Vector<double> last_good = m.u;
    const double last_good_pressure = m.cavity.pressure;
    double reference = -1;
    if (predict) {
      Vector<double> load(m.dof.n_dofs());
      for (std::size_t a = 0; a < m.patches.size(); ++a)
        for (int c = 0; c < 3; ++c) {
          const double df = m.patches[a].force[c] - m.patches[a].converged_force[c];
          load.add(df, m.patches[a].h[c]);
          m.u.add(df, m.compliance_columns[3 * a + c]);
        }
      m.constraints.set_zero(load);
      reference = load.l2_norm();
    }
    StepReport step = m.newton(target, s, reference);
    report.total_iterations += static_cast<int>(step.residuals.size()) - 1;
    const bool ok = step.converged;
    report.steps.push_back(step);
    if (ok) {
      done = target;
      predict = false;
      continue;
    }
    m.u = last_good;  // roll back the step
    m.cavity.pressure = last_good_pressure;
    if (predict) {  // retry the same step from the last converged state
      predict = false;
      m.tangent_current = false;
      continue;
    }
    predict = false;
    m.tangent_current = false;
    m.tangent.refactor_next();  // the retry starts from a state the factorisation may not fit
    if (++report.cuts > s.max_cuts) {
      m.u = initial;  // and the whole solve: the state stays the last converged one
      m.cavity.pressure = initial_pressure;
      m.tangent_current = false;
      report.failure = "load step at factor " + std::to_string(target) + " failed after " + std::to_string(s.max_cuts) +
                       " cuts: " + step.failure;
      times();
      return report;
    }
    increment /= 2;
  }
  report.converged = true;
  times();
  m.static_done = 1;
  if (m.dynamic) {  // advance the time-stepping state
    for (types::global_dof_index i = 0; i < m.u.size(); ++i) {
      const double a_new = m.acceleration(m.u[i], i);
      const double v_new = m.velocity(m.u[i], a_new, i);
      m.a_old[i] = a_new;
      m.v_old[i] = v_new;
    }
  }
  for (auto& p : m.patches) p.converged_force = p.force;
  return report;
}

Tensor<1, 3> QuasiStaticSolver::boundary_force(unsigned int boundary_id) const {
  Vector<double> r(impl_->dof.n_dofs()), internal(impl_->dof.n_dofs());
  if (!impl_->assemble(1.0, r, false, &internal)) throw std::runtime_error("boundary_force: an element is inverted");
  Tensor<1, 3> force;
  for (int c = 0; c < 3; ++c) {
    ComponentMask mask(3, false);
    mask.set(c, true);
    const IndexSet dofs = DoFTools::extract_boundary_dofs(impl_->dof, mask, {types::boundary_id(boundary_id)});
    for (const auto i : dofs) force[c] += internal[i];
  }
  return force;
}

Tensor<1, 3> QuasiStaticSolver::displacement_at(const Point<3>& point) const {
  Vector<double> value(3);
  VectorTools::point_value(*impl_->mapping, impl_->dof, impl_->u, point, value);
  Tensor<1, 3> t;
  for (int c = 0; c < 3; ++c) t[c] = value[c];
  return t;
}

double QuasiStaticSolver::max_nodal_error(const std::function<Tensor<1, 3>(const Point<3>&)>& exact) const {
  std::map<types::global_dof_index, Point<3>> points;
  DoFTools::map_dofs_to_support_points(*impl_->mapping, impl_->dof, points);
  double worst = 0;
  const std::vector<int> component = impl_->dof_components();
  for (const auto& [index, point] : points) worst = std::max(worst, std::abs(impl_->u[index] - exact(point)[component[index]]));
  return worst;
}

}  // namespace fetouch::fem
