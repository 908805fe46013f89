#include "fem/contact_patches.h"

#include <deal.II/fe/fe_values.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_values_extractors.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

namespace fetouch::fem {

using namespace dealii;

namespace {

// A face larger than the patch would put few or none of its quadrature points under the kernel (a
// 1 mm probe on 50 mm faces: none, and no patch). Such a face is integrated on its subdivision into
// m x m similar pieces, m = ceil(face diameter / radius), each with a low-order rule (2 x 2 Gauss
// points on a quadrilateral, 3 on a triangle: the kernel is smooth on a piece no larger than the
// radius) mapped into it: the kernel is then sampled at spacings no coarser than on a face of the
// radius's size, whatever the mesh, and the integral (hence H, the force's distribution and W)
// converges with the mesh as on fine faces. A face no larger than the radius keeps its rule (m = 1).
constexpr unsigned int kMaxSubdivisions = 64;

unsigned int face_subdivisions(double face_diameter, double radius) {
  const double m = std::ceil(face_diameter / radius);
  return m <= 1 ? 1 : static_cast<unsigned int>(std::min<double>(m, kMaxSubdivisions));
}

// The rule `base` on the reference face (unit square, or the triangle (0,0), (1,0), (0,1)) copied
// into each of its m x m pieces by the affine map of that piece.
Quadrature<2> subdivided(const Quadrature<2>& base, bool triangle, unsigned int m) {
  std::vector<Point<2>> points;
  std::vector<double> weights;
  const double h = 1.0 / m;
  const auto copy = [&](const Point<2>& origin, const Tensor<1, 2>& e0, const Tensor<1, 2>& e1) {
    const double area = std::abs(e0[0] * e1[1] - e0[1] * e1[0]);  // of the piece, in units of the face's
    for (unsigned int q = 0; q < base.size(); ++q) {
      const Point<2>& x = base.point(q);
      points.push_back(origin + x[0] * e0 + x[1] * e1);
      weights.push_back(base.weight(q) * area);
    }
  };
  const Tensor<1, 2> ex({h, 0}), ey({0, h});
  for (unsigned int i = 0; i < m; ++i)
    for (unsigned int j = 0; j < m; ++j) {
      const Point<2> corner(i * h, j * h);
      if (!triangle) {
        copy(corner, ex, ey);
        continue;
      }
      if (i + j < m) copy(corner, ex, ey);                     // the piece pointing like the face
      if (i + j + 1 < m) copy(corner + ex + ey, -ex, -ey);     // the one pointing the other way
    }
  return Quadrature<2>(points, weights);
}

}  // namespace

// The face values of a subdivision and flags, built once (their set-up, every face orientation
// of every face of the reference cell, costs far more than a reinit).
FEFaceValues<3>& ContactPatchesTerm::face_values(unsigned int m, UpdateFlags flags) const {
  std::unique_ptr<FEFaceValues<3>>& values = face_values_[{m, static_cast<unsigned int>(flags)}];
  if (!values) {
    const Quadrature<2> rule = m == 1 ? *d_.face_quadrature
                                      : subdivided(d_.simplex ? Quadrature<2>(QGaussSimplex<2>(2)) : Quadrature<2>(QGauss<2>(2)),
                                                   d_.simplex, m);
    values = std::make_unique<FEFaceValues<3>>(*d_.mapping, *d_.fe, rule, flags);
  }
  return *values;
}

// Calls visit(cell, face_values, q, w, first) at every boundary quadrature point within a patch's
// radius: w = (1 - (d/r)^2)^2 JxW is the unnormalised kernel weight, `first` marks the first point
// visited on a face (to evaluate per-face data once); face_values carries `flags`.
template <class Visit>
void ContactPatchesTerm::for_each_patch_point(const Patch& p, UpdateFlags flags, Visit visit) const {
  flags = flags | update_JxW_values | update_quadrature_points;
  for (const Discretisation::BoundaryFace& face : d_.boundary_faces()) {
    // Skip faces that are entirely out of reach (a cheap bound through the face's diameter).
    if (face.center.distance(p.center) > p.radius + face.diameter) continue;
    FEFaceValues<3>& values = face_values(face_subdivisions(face.diameter, p.radius), flags);
    values.reinit(face.cell, face.face);
    bool first = true;
    for (unsigned int q = 0; q < values.n_quadrature_points; ++q) {
      const double r = values.quadrature_point(q).distance(p.center) / p.radius;
      if (r >= 1) continue;
      visit(face.cell, values, q, (1 - r * r) * (1 - r * r) * values.JxW(q), first);
      first = false;
    }
  }
}

ContactPatchesTerm::ContactPatchesTerm(const Discretisation& discretisation) : d_(discretisation) {}
ContactPatchesTerm::~ContactPatchesTerm() = default;

void ContactPatchesTerm::build(Patch& p) const {
  const unsigned int n = d_.fe->n_dofs_per_cell();
  std::vector<types::global_dof_index> indices(n);
  for (Vector<double>& row : p.h) row.reinit(d_.n_dofs());
  double total = 0;
  for_each_patch_point(p, update_values,
                       [&](const auto& cell, const FEFaceValues<3>& values, unsigned int q, double w, bool first) {
                         total += w;
                         if (first) cell->get_dof_indices(indices);
                         for (unsigned int i = 0; i < n; ++i) {
                           const unsigned int c = d_.fe->system_to_component_index(i).first;
                           p.h[c][indices[i]] += w * values.shape_value_component(i, q, c);
                         }
                       });
  if (!(total > 0)) throw std::invalid_argument("contact patch: no boundary surface within the radius of its centre");
  for (Vector<double>& row : p.h) row /= total;
}

int ContactPatchesTerm::add(const Point<3>& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("contact patch: the radius must be positive");
  Patch patch{center, radius, {}, Tensor<1, 3>(), Tensor<1, 3>()};
  build(patch);
  patches_.push_back(std::move(patch));
  return size() - 1;
}

void ContactPatchesTerm::move(int patch, const Point<3>& center) {
  Patch& p = patches_.at(patch);
  Patch moved{center, p.radius, {}, p.force, p.converged_force};
  build(moved);
  p = std::move(moved);
}

bool ContactPatchesTerm::forces_changed() const {
  for (const Patch& p : patches_)
    if (p.force != p.converged_force) return true;
  return false;
}

bool ContactPatchesTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const double lambda = state.patch_lambda;
  for (const Patch& p : patches_)
    for (int comp = 0; comp < 3; ++comp) {
      const double f = p.converged_force[comp] + lambda * (p.force[comp] - p.converged_force[comp]);
      if (f == 0) continue;
      const Vector<double>& h = p.h[comp];
      for (types::global_dof_index i = 0; i < h.size(); ++i) {
        if (h[i] == 0) continue;
        target.residual[i] += f * h[i];
        if (target.internal) target.internal[i] -= f * h[i];
      }
    }
  return true;
}

void ContactPatchesTerm::accept(const Vector<double>&) {
  for (Patch& p : patches_) p.converged_force = p.force;
}

Tensor<1, 3> ContactPatchesTerm::displacement(int patch, const Vector<double>& u) const {
  const Patch& p = patches_.at(patch);
  Tensor<1, 3> d;
  for (int c = 0; c < 3; ++c) d[c] = p.h[c] * u;
  return d;
}

Tensor<1, 3> ContactPatchesTerm::deformed_normal(int patch, const Vector<double>& u) const {
  const Patch& p = patches_.at(patch);
  const FEValuesExtractors::Vector displacement(0);
  std::vector<Tensor<2, 3>> grad_u;
  Tensor<1, 3> sum;
  for_each_patch_point(p, update_gradients | update_normal_vectors,
                       [&](const auto&, const FEFaceValues<3>& values, unsigned int q, double w, bool first) {
                         if (first) {
                           grad_u.resize(values.n_quadrature_points);
                           values[displacement].get_function_gradients(u, grad_u);
                         }
                         Tensor<2, 3> F = grad_u[q];
                         for (int i = 0; i < 3; ++i) F[i][i] += 1;
                         sum += w * (determinant(F) * transpose(invert(F)) * values.normal_vector(q));
                       });
  return sum / sum.norm();
}

}  // namespace fetouch::fem
