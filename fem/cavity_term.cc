#include "fem/cavity_term.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

namespace {

void check_supported(const Discretisation& d, const CavityLaw& law) {
  if (d.fe->degree != 1 && d.fe->degree != 2)
    throw std::invalid_argument("cavity: the wall's faces are taken as linear or quadratic; use elements of degree 1 or 2");
  if (law.gas ? !(law.initial_pressure_pa > 0) : !(law.bulk_modulus_pa > 0))
    throw std::invalid_argument("cavity: a gas needs a positive initial pressure, a liquid a positive bulk modulus");
}

// Face f of `cell` as one triangle (a quadrilateral as two) of the wall, its normal pointing into
// the cell (`into_cell`) or out of it: always out of the cavity.
template <class Cell>
void add_face(const Discretisation& d, const Cell& cell, unsigned int f, bool into_cell, CavityWall& wall) {
  std::vector<types::global_dof_index> indices(d.fe->n_dofs_per_cell());
  const auto face = cell->face(f);
  cell->get_dof_indices(indices);
  const auto triangle = [&](unsigned int a, unsigned int b, unsigned int c) {
    CavityWall::Triangle t;
    const unsigned int vs[3] = {a, b, c};
    for (int v = 0; v < 3; ++v) {
      // The face vertex's index in the cell, then its dof of each component.
      unsigned int in_cell = 0;
      while (cell->vertex_index(in_cell) != face->vertex_index(vs[v])) ++in_cell;
      for (unsigned int k = 0; k < 3; ++k) {
        t.dofs[v][k] = static_cast<unsigned int>(indices[d.fe->component_to_system_index(k, in_cell)]);
        t.position[v][k] = face->vertex(vs[v])[k];
      }
    }
    const Point<3> pa = face->vertex(a), pb = face->vertex(b), pc = face->vertex(c);
    const Tensor<1, 3> normal = cross_product_3d(pb - pa, pc - pa);
    const bool points_in = normal * (cell->center() - face->center()) > 0;
    if (points_in != into_cell) std::swap(t.dofs[1], t.dofs[2]), std::swap(t.position[1], t.position[2]);
    wall.triangles.push_back(t);
  };
  if (face->n_vertices() == 3) {
    triangle(0, 1, 2);
  } else {  // deal.II's quadrilateral vertices 0, 1, 3, 2 go around the face
    triangle(0, 1, 3);
    triangle(0, 3, 2);
  }
}

// A quadratic element's face f of `cell` as a curved face of the wall through its nodes: the cell's
// dofs whose support points are the face's corners, edge midpoints (and a quadrilateral's centre).
// The mapping is linear, so the nodes sit exactly there; they are found by position.
template <class Cell>
void add_quadratic_face(const Discretisation& d, const Cell& cell, unsigned int f, bool into_cell, CavityWall& wall) {
  const auto face = cell->face(f);
  std::vector<types::global_dof_index> indices(d.fe->n_dofs_per_cell());
  cell->get_dof_indices(indices);
  const std::vector<Point<3>>& unit = d.fe->get_unit_support_points();
  std::vector<Point<3>> support(unit.size());
  for (std::size_t i = 0; i < unit.size(); ++i) support[i] = d.mapping->transform_unit_to_real_cell(cell, unit[i]);
  std::vector<Point<3>> nodes;
  if (face->n_vertices() == 3) nodes = {face->vertex(0), face->vertex(1), face->vertex(2)};
  else nodes = {face->vertex(0), face->vertex(1), face->vertex(3), face->vertex(2)};  // around the face
  const std::size_t corners = nodes.size();
  const Tensor<1, 3> normal = corners == 3 ? cross_product_3d(nodes[1] - nodes[0], nodes[2] - nodes[0])
                                           : cross_product_3d(nodes[2] - nodes[0], nodes[3] - nodes[1]);
  const bool points_in = normal * (cell->center() - face->center()) > 0;
  if (points_in != into_cell) std::swap(nodes[1], nodes[corners - 1]);
  for (std::size_t e = 0; e < corners; ++e) nodes.push_back((nodes[e] + nodes[(e + 1) % corners]) / 2);
  if (corners == 4) nodes.push_back((nodes[0] + nodes[1] + nodes[2] + nodes[3]) / 4);
  CavityWall::QuadraticFace q;
  q.nodes = static_cast<unsigned int>(nodes.size());
  const double tolerance = 1e-8 * cell->diameter();
  for (unsigned int a = 0; a < q.nodes; ++a) {
    for (unsigned int k = 0; k < 3; ++k) {
      std::size_t i = 0;
      const auto elsewhere = [&](std::size_t j) {
        return d.fe->system_to_component_index(j).first != k || support[j].distance(nodes[a]) > tolerance;
      };
      while (i < support.size() && elsewhere(i)) ++i;
      if (i == support.size()) throw std::logic_error("cavity: a quadratic face's node is not a dof of its cell");
      q.dofs[a][k] = static_cast<unsigned int>(indices[i]);
      q.position[a][k] = nodes[a][k];
    }
  }
  wall.quadratic_faces.push_back(q);
}

template <class Cell>
void add_wall_face(const Discretisation& d, const Cell& cell, unsigned int f, bool into_cell, CavityWall& wall) {
  if (d.fe->degree == 1) add_face(d, cell, f, into_cell, wall);
  else add_quadratic_face(d, cell, f, into_cell, wall);
}

}  // namespace

CavityTerm::CavityTerm(const Discretisation& d, unsigned int boundary_id, const CavityLaw& law) : law_(law) {
  check_supported(d, law);
  for (const auto& cell : d.dof.active_cell_iterators())
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == boundary_id) add_wall_face(d, cell, f, true, wall_);
  if (wall_.triangles.empty() && wall_.quadratic_faces.empty())
    throw std::invalid_argument("cavity: no boundary face has the cavity's boundary id " + std::to_string(boundary_id));
  finish_setup(d, "the surface with boundary id " + std::to_string(boundary_id));
}

CavityTerm::CavityTerm(const Discretisation& d, const std::set<unsigned int>& contents, const CavityLaw& law)
    : law_(law) {
  check_supported(d, law);
  const auto inside = [&](const auto& cell) { return contents.count(cell->material_id()) > 0; };
  bool any = false, all = true;
  for (const auto& cell : d.dof.active_cell_iterators()) {
    if (!inside(cell)) {
      all = false;
      continue;
    }
    any = true;
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary() || !inside(cell->neighbor(f))) add_wall_face(d, cell, f, false, wall_);
  }
  if (!any) throw std::invalid_argument("cavity: no cell belongs to the cavity's regions");
  if (all) throw std::invalid_argument("cavity: the cavity's regions are the whole body: no wall holds them");
  finish_setup(d, "the cavity's regions");
}

void CavityTerm::finish_setup(const Discretisation& d, const std::string& what) {
  const Vector<double> zero(d.n_dofs());
  reference_volume_ = wall_.volume(zero.begin());
  if (!(reference_volume_ > 0))
    throw std::invalid_argument("cavity: " + what + " does not enclose a volume (not closed, or not an inner surface)");
  g_.reinit(d.n_dofs());
  pressure_ = step_start_ = law_.initial_pressure_pa;
}

// p g into r (and -p g into `internal`), -p d2V into the tangent, and the law's residual; false if
// the cavity collapsed (V <= 0).
bool CavityTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const Vector<double>& u = state.u;
  const std::vector<bool>& constrained = target.system->constrained();
  const double volume = wall_.volume(u.begin());
  if (!(volume > 0)) return false;
  const double p = pressure_;
  volume_residual_ = volume - law_.volume(p, reference_volume_);
  g_ = 0;
  wall_.add_gradient(u.begin(), 1.0, g_.begin());
  for (types::global_dof_index i = 0; i < u.size(); ++i) {
    if (target.internal) target.internal[i] -= p * g_[i];
    if (constrained[i]) g_[i] = 0;
    else target.residual[i] += p * g_[i];
  }
  if (target.tangent) {
    const LinearSystem& system = *target.system;
    if (positions_revision_ != system.pattern_revision()) {  // where each Hessian entry goes, found once
      positions_.clear();
      wall_.add_hessian(u.begin(), 0.0, [&](unsigned int row, unsigned int column, double) {
        positions_.push_back(constrained[row] || constrained[column] ? -1 : system.position(int(row), int(column)));
      });
      positions_revision_ = system.pattern_revision();
    }
    std::size_t k = 0;
    wall_.add_hessian(u.begin(), -p, [&](unsigned int, unsigned int, double value) {
      if (const int at = positions_[k++]; at >= 0) target.tangent[at] += value;
    });
    stiffness_ = -1 / law_.volume_derivative(p, reference_volume_);  // -dp/dV of the law
  }
  return true;
}

bool CavityTerm::rank_one(double& c, const Vector<double>*& g) const {
  c = stiffness_;
  g = &g_;
  return stiffness_ != 0;
}

// The pressure's step: K_s du - g dp = r, g'du - V_law'(p) dp = -(V - V_law), i.e. with
// c = -1/V_law'(p), dp = -c (r_V + g'du) and (K_s + c g g') du = r - c r_V g: the linear system
// solves with the rank-one part and this load, and the pressure follows from du. (Its cancellation
// in r_V + g'du costs the digits of c g'y / (1 + c g'y), y = K_s^-1 g: about 6 of 16 for water.)
double CavityTerm::rank_one_load() const { return -stiffness_ * volume_residual_; }

void CavityTerm::complete_step(const LinearSystem& /*system*/, Vector<double>& du) {
  dp_ = -stiffness_ * (volume_residual_ + g_ * du);
  step_start_ = pressure_;
}

// A pressure change dp with the deformation it causes, du = dp K_s^-1 g, keeps K_s du - g dp = 0:
// moving along it changes only the volume. With w = (P + c g g')^-1 g = P^-1 g / (1 + c g'P^-1 g)
// (P the factorisation of a recent K_s) the pair u += t w, p += t (1 - c g'w) keeps the force
// balance to first order and moves the law's residual by t / c: t = -c r_V restores it.
// The restoration moves the wall's nodal forces by about |c r_V| |g|_inf: when that is negligible
// (a frame whose prediction kept the volume: every frame before a touch) it is skipped, and with it
// P^-1 g for the moved g (a solve with the factorisation, 44 ms on the anatomy at 3.6 mm).
bool CavityTerm::restore(Vector<double>& u, LinearSystem& system, double negligible_force) {
  if (stiffness_ == 0 || system.rank_one_g() != &g_) return false;
  const double residual = wall_.volume(u.begin()) - law_.volume(pressure_, reference_volume_);
  if (residual == 0 || std::abs(stiffness_ * residual) * g_.linfty_norm() <= negligible_force) return false;
  system.apply_factorisation_to_rank_one_g(w_);
  const double t = -stiffness_ * residual;
  u.add(t, w_);
  pressure_ += t * (1 - stiffness_ * (g_ * w_));
  return true;
}

}  // namespace fetouch::fem
