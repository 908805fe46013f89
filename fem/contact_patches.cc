#include "fem/contact_patches.h"

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/fe_values_extractors.h>

#include <stdexcept>

namespace fetouch::fem {

using namespace dealii;

namespace {

// Calls visit(cell, face_values, q, w, first) at every boundary quadrature point within a patch's
// radius: w = (1 - (d/r)^2)^2 JxW is the unnormalised kernel weight, `first` marks the first point
// visited on a face (to evaluate per-face data once); face_values carries `flags`.
template <class Visit>
void for_each_patch_point(const Discretisation& d, const ContactPatchesTerm::Patch& p, UpdateFlags flags, Visit visit) {
  FEFaceValues<3> face_values(*d.mapping, *d.fe, *d.face_quadrature, flags | update_JxW_values | update_quadrature_points);
  for (const auto& cell : d.dof.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      // Skip faces that are entirely out of reach (a cheap bound through the face's diameter).
      if (cell->face(f)->center().distance(p.center) > p.radius + cell->face(f)->diameter()) continue;
      face_values.reinit(cell, f);
      bool first = true;
      for (unsigned int q = 0; q < d.face_quadrature->size(); ++q) {
        const double r = face_values.quadrature_point(q).distance(p.center) / p.radius;
        if (r >= 1) continue;
        visit(cell, face_values, q, (1 - r * r) * (1 - r * r) * face_values.JxW(q), first);
        first = false;
      }
    }
}

}  // namespace

void ContactPatchesTerm::build(Patch& p) const {
  const unsigned int n = d_.fe->n_dofs_per_cell();
  std::vector<types::global_dof_index> indices(n);
  for (Vector<double>& row : p.h) row.reinit(d_.n_dofs());
  double total = 0;
  for_each_patch_point(d_, p, update_values,
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
  std::vector<Tensor<2, 3>> grad_u(d_.face_quadrature->size());
  Tensor<1, 3> sum;
  for_each_patch_point(d_, p, update_gradients | update_normal_vectors,
                       [&](const auto&, const FEFaceValues<3>& values, unsigned int q, double w, bool first) {
                         if (first) values[displacement].get_function_gradients(u, grad_u);
                         Tensor<2, 3> F = grad_u[q];
                         for (int i = 0; i < 3; ++i) F[i][i] += 1;
                         sum += w * (determinant(F) * transpose(invert(F)) * values.normal_vector(q));
                       });
  return sum / sum.norm();
}

}  // namespace fetouch::fem
