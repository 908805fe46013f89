#include "fem/quasi_static_solver.h"

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
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/petsc_solver.h>
#include <deal.II/lac/petsc_sparse_matrix.h>
#include <deal.II/lac/petsc_vector.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_component_interpretation.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools.h>

#include <petscksp.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <stdexcept>

namespace fetouch::fem {

using namespace dealii;

namespace {

// PETSc's MUMPS Cholesky factorisation, kept for several right-hand sides (the Newton step, then
// the 3m compliance columns, reuse one factorisation).
class CholeskySolver {
 public:
  ~CholeskySolver() { reset(); }
  // The first call creates the solver (symbolic analysis and numeric factorisation); later calls
  // with a matrix of the same sparsity refactor numerically only, reusing MUMPS's analysis.
  void factor(const PETScWrappers::MatrixBase& matrix, MPI_Comm comm) {
    const Mat mat = static_cast<Mat>(matrix);
    if (ksp_ && mat != matrix_) reset();
    if (!ksp_) {
      check(KSPCreate(comm, &ksp_));
      check(KSPSetType(ksp_, KSPPREONLY));
      PC pc;
      check(KSPGetPC(ksp_, &pc));
      check(PCSetType(pc, PCCHOLESKY));
      check(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
    }
    matrix_ = mat;
    check(KSPSetOperators(ksp_, mat, mat));
    check(KSPSetUp(ksp_));
  }
  void reset_if(const PETScWrappers::MatrixBase& matrix) {
    if (static_cast<Mat>(matrix) == matrix_) reset();
  }
  void solve(const PETScWrappers::MPI::Vector& b, PETScWrappers::MPI::Vector& x) {
    check(KSPSolve(ksp_, static_cast<const Vec&>(b), static_cast<const Vec&>(x)));
  }

 private:
  static void check(PetscErrorCode code) {
    if (code != 0) throw std::runtime_error("PETSc error " + std::to_string(code) + " in the direct solver");
  }
  void reset() {
    if (ksp_) KSPDestroy(&ksp_);
    ksp_ = nullptr;
    matrix_ = nullptr;
  }
  KSP ksp_ = nullptr;
  Mat matrix_ = nullptr;
};

}  // namespace

struct QuasiStaticSolver::Impl {
  const Triangulation<3>& tria;
  const Material& material;
  bool simplex;
  std::unique_ptr<FiniteElement<3>> fe;
  std::unique_ptr<Mapping<3>> mapping;
  std::unique_ptr<Quadrature<3>> quadrature;
  std::unique_ptr<Quadrature<2>> face_quadrature;
  DoFHandler<3> dof;
  AffineConstraints<double> constraints;  // homogeneous: the Newton update's
  PETScWrappers::MPI::SparseMatrix matrix;
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
  CholeskySolver direct;
  // Phase timers of the running solve, and of the last compliance.
  double assembly_s = 0, factorisation_s = 0, solve_s = 0;
  ComplianceTimes compliance_times;
  static double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  Impl(const Triangulation<3>& t, const Material& m, int degree) : tria(t), material(m), dof(t) {
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
    u.reinit(dof.n_dofs());
  }

  bool set_up = false;  // constraints and sparsity for the current supports
  void setup_constraints() {
    if (set_up) return;
    direct.reset_if(matrix);  // the matrix is rebuilt: a new factorisation follows
    set_up = true;
    constraints.clear();
    for (const Prescribed& p : prescribed)
      VectorTools::interpolate_boundary_values(*mapping, dof, p.boundary, Functions::ZeroFunction<3>(3), constraints,
                                               ComponentMask({p.components[0], p.components[1], p.components[2]}));
    constraints.close();
    DynamicSparsityPattern dsp(dof.n_dofs());
    DoFTools::make_sparsity_pattern(dof, dsp, constraints, /*keep_constrained_dofs=*/false);
    const IndexSet owned = complete_index_set(dof.n_dofs());
    matrix.reinit(owned, owned, dsp, MPI_COMM_SELF);
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
  // d(a + alpha v)/du+ for the tangent.
  double inertia_gain() const {
    const double dt = dynamics.time_step_s;
    const double dv = dynamics.newmark ? dynamics.gamma * dt * c0 : 1 / dt;
    return c0 + dynamics.rayleigh_mass_per_s * dv;
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
    for (const auto& cell : dof.active_cell_iterators()) {
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

  bool assemble_impl(double lambda, Vector<double>& r, bool tangent, Vector<double>* internal) {
    if (!cache.built) build_cache();
    const Cache& c = cache;
    // With inertia: a+ + alpha v+ at every dof, once per assembly (not once per cell sharing it).
    Vector<double> inertial;
    if (dynamic) {
      inertial.reinit(u.size());
      for (types::global_dof_index i = 0; i < u.size(); ++i) {
        const double a_new = acceleration(u[i], i);
        inertial[i] = a_new + dynamics.rayleigh_mass_per_s * velocity(u[i], a_new, i);
      }
    }
    std::vector<double> inertial_local(dynamic ? c.n : 0);
    const unsigned int n = c.n, nq = c.nq;
    FullMatrix<double> cell_matrix(n, n);
    Vector<double> cell_rhs(n), cell_internal(n);
    std::vector<types::global_dof_index> indices(n);
    std::vector<double> u_local(n);
    std::vector<std::array<Tensor<1, 3>, 3>> a_grad(n);
    r = 0;
    if (internal) *internal = 0;
    if (tangent) matrix = 0;
    Tensor2 P;
    Tensor4 A;
    const unsigned int cells = tria.n_active_cells();
    for (unsigned int k = 0; k < cells; ++k) {
      std::copy_n(c.indices.begin() + std::size_t(k) * n, n, indices.begin());
      gather(k, u, u_local);
      cell_matrix = 0;
      cell_internal = 0;
      for (unsigned int q = 0; q < nq; ++q) {
        const Tensor<1, 3>* grad = &c.gradients[(std::size_t(k) * nq + q) * c.nbase];
        const double jxw = c.jxw[std::size_t(k) * nq + q];
        if (!material.evaluate(deformation_gradient(k, q, u_local), P, tangent ? &A : nullptr)) {
          if (tangent) matrix.compress(VectorOperation::add);  // leave PETSc's matrix usable
          return false;
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
      for (unsigned int i = 0; i < n; ++i) cell_rhs(i) = -cell_internal(i);
      if (internal) internal->add(indices, cell_internal);
      if (tangent)
        constraints.distribute_local_to_global(cell_matrix, cell_rhs, indices, matrix, r);
      else
        constraints.distribute_local_to_global(cell_rhs, indices, r);
    }
    if (tangent) matrix.compress(VectorOperation::add);
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

  // x = K^-1 rhs with the current factorisation (constrained entries of x set by the constraints).
  void solve_factored(const Vector<double>& rhs, Vector<double>& x) {
    const IndexSet owned = complete_index_set(dof.n_dofs());
    PETScWrappers::MPI::Vector b(owned, MPI_COMM_SELF), solution(owned, MPI_COMM_SELF);
    for (types::global_dof_index i = 0; i < rhs.size(); ++i) b[i] = rhs[i];
    b.compress(VectorOperation::insert);
    direct.solve(b, solution);
    x.reinit(rhs.size());
    for (types::global_dof_index i = 0; i < rhs.size(); ++i) x[i] = solution[i];
    constraints.distribute(x);
  }

  void solve_linear(const Vector<double>& rhs, Vector<double>& du) {
    auto start = std::chrono::steady_clock::now();
    direct.factor(matrix, MPI_COMM_SELF);
    factorisation_s += since(start);
    start = std::chrono::steady_clock::now();
    solve_factored(rhs, du);
    solve_s += since(start);
  }

  StepReport newton(double lambda, const NewtonSettings& s) {
    StepReport report;
    report.load_factor = lambda;
    apply_prescribed(lambda);
    Vector<double> r(dof.n_dofs()), du, trial_r(dof.n_dofs());
    double reference = -1;
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
      if (norm <= s.relative_tolerance * reference || norm <= s.absolute_tolerance) {
        report.converged = true;
        report.iterations = it;
        return report;
      }
      if (it == s.max_iterations) break;
      solve_linear(r, du);
      // Backtracking: halve until the residual decreases and no element inverts. The full step is
      // assembled with its tangent, which the next iteration then reuses (one assembly per Newton
      // iteration when the full step is taken, as it is near convergence).
      const Vector<double> start = u;
      double alpha = 1;
      bool accepted = false;
      for (int b = 0; b < 10 && !accepted; ++b, alpha /= 2) {
        u = start;
        u.add(alpha, du);
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
        report.failure = "the line search found no admissible step";
        return report;
      }
    }
    report.iterations = s.max_iterations;
    report.failure = "no convergence in " + std::to_string(s.max_iterations) + " Newton iterations";
    return report;
  }
};

QuasiStaticSolver::QuasiStaticSolver(const Triangulation<3>& triangulation, const Material& material, int degree)
    : impl_(std::make_unique<Impl>(triangulation, material, degree)) {}

QuasiStaticSolver::~QuasiStaticSolver() = default;

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
      if (j > 0 && m.material.evaluate(F, P, nullptr)) {
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

void QuasiStaticSolver::write_vtu(const std::string& path) const {
  const Impl& m = *impl_;
  DataOut<3> out;
  out.attach_dof_handler(m.dof);
  const std::vector<std::string> names(3, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> kinds(
      3, DataComponentInterpretation::component_is_part_of_vector);
  out.add_data_vector(m.u, names, DataOut<3>::type_dof_data, kinds);
  const CellFields fields = cell_fields();
  Vector<double> jacobian(fields.jacobian.begin(), fields.jacobian.end());
  Vector<double> von_mises(fields.von_mises.begin(), fields.von_mises.end());
  out.add_data_vector(jacobian, "J", DataOut<3>::type_cell_data);
  out.add_data_vector(von_mises, "von_mises_stress_pa", DataOut<3>::type_cell_data);
  out.build_patches(*m.mapping, m.fe->degree);
  std::ofstream file(path);
  if (!file) throw std::runtime_error("cannot write " + path);
  out.write_vtu(file);
  if (!file) throw std::runtime_error("cannot write " + path);
}

int QuasiStaticSolver::add_contact_patch(const Point<3>& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("contact patch: the radius must be positive");
  Impl::Patch patch{center, radius, {}, Tensor<1, 3>(), Tensor<1, 3>()};
  impl_->build_patch(patch);
  impl_->patches.push_back(std::move(patch));
  return static_cast<int>(impl_->patches.size()) - 1;
}

void QuasiStaticSolver::set_patch_force(int patch, const Tensor<1, 3>& force) { impl_->patches.at(patch).force = force; }

Tensor<1, 3> QuasiStaticSolver::patch_displacement(int patch) const {
  const auto& p = impl_->patches.at(patch);
  Tensor<1, 3> d;
  for (int c = 0; c < 3; ++c) d[c] = p.h[c] * impl_->u;
  return d;
}

const ComplianceTimes& QuasiStaticSolver::last_compliance_times() const { return impl_->compliance_times; }

Point<3> QuasiStaticSolver::patch_center(int patch) const { return impl_->patches.at(patch).center; }

int QuasiStaticSolver::patches() const { return static_cast<int>(impl_->patches.size()); }

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
  Vector<double> r(m.dof.n_dofs());
  auto start = std::chrono::steady_clock::now();
  if (!m.assemble(1.0, r, /*tangent=*/true)) throw std::runtime_error("compliance: an element is inverted");
  m.compliance_times.assembly_s = Impl::since(start);
  start = std::chrono::steady_clock::now();
  m.direct.factor(m.matrix, MPI_COMM_SELF);
  m.compliance_times.factorisation_s = Impl::since(start);
  start = std::chrono::steady_clock::now();
  const unsigned int columns = 3 * m.patches.size();
  std::vector<Vector<double>> solutions(columns);
  for (unsigned int k = 0; k < columns; ++k) {
    Vector<double> rhs = m.patches[k / 3].h[k % 3];
    m.constraints.set_zero(rhs);
    m.solve_factored(rhs, solutions[k]);
  }
  m.compliance_times.solves_s = Impl::since(start);
  FullMatrix<double> w(columns, columns);
  for (unsigned int a = 0; a < columns; ++a)
    for (unsigned int b = 0; b < columns; ++b) w(a, b) = m.patches[a / 3].h[a % 3] * solutions[b];
  return w;
}

void QuasiStaticSolver::enable_dynamics(const Dynamics& dynamics) {
  if (!(dynamics.time_step_s > 0) || !(dynamics.density_kg_per_m3 > 0))
    throw std::invalid_argument("dynamics: the time step and the density must be positive");
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
  impl_->setup_constraints();
  const Vector<double> initial = impl_->u;
  if (impl_->dynamic) impl_->u_old = initial;
  impl_->assembly_s = impl_->factorisation_s = impl_->solve_s = 0;
  SolveReport report;
  const auto times = [&] {
    report.assembly_s = impl_->assembly_s, report.factorisation_s = impl_->factorisation_s, report.solve_s = impl_->solve_s;
  };
  double done = 0, increment = 1.0 / std::max(1, s.load_steps);
  while (done < 1 - 1e-12) {
    const double target = std::min(1.0, done + increment);
    const Vector<double> last_good = impl_->u;
    StepReport step = impl_->newton(target, s);
    report.total_iterations += static_cast<int>(step.residuals.size()) - 1;
    const bool ok = step.converged;
    report.steps.push_back(step);
    if (ok) {
      done = target;
      continue;
    }
    impl_->u = last_good;  // roll back the step
    if (++report.cuts > s.max_cuts) {
      impl_->u = initial;  // and the whole solve: the state stays the last converged one
      report.failure = "load step at factor " + std::to_string(target) + " failed after " + std::to_string(s.max_cuts) +
                       " cuts: " + step.failure;
      times();
      return report;
    }
    increment /= 2;
  }
  report.converged = true;
  times();
  impl_->static_done = 1;
  if (impl_->dynamic) {  // advance the time-stepping state
    Impl& m = *impl_;
    for (types::global_dof_index i = 0; i < m.u.size(); ++i) {
      const double a_new = m.acceleration(m.u[i], i);
      const double v_new = m.velocity(m.u[i], a_new, i);
      m.a_old[i] = a_new;
      m.v_old[i] = v_new;
    }
  }
  for (auto& p : impl_->patches) p.converged_force = p.force;
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
  // The component of each dof, from the cells (whatever the numbering).
  std::vector<int> component(impl_->dof.n_dofs(), -1);
  std::vector<types::global_dof_index> indices(impl_->fe->n_dofs_per_cell());
  for (const auto& cell : impl_->dof.active_cell_iterators()) {
    cell->get_dof_indices(indices);
    for (unsigned int i = 0; i < indices.size(); ++i) component[indices[i]] = impl_->fe->system_to_component_index(i).first;
  }
  for (const auto& [index, point] : points) worst = std::max(worst, std::abs(impl_->u[index] - exact(point)[component[index]]));
  return worst;
}

}  // namespace fetouch::fem
