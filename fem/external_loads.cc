#include "fem/external_loads.h"

#include <deal.II/fe/fe_values.h>

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

void ExternalLoadsTerm::add_traction(unsigned int boundary_id, const Tensor<1, 3>& traction) {
  tractions_.push_back({boundary_id, traction});
  built_ = false;
}

void ExternalLoadsTerm::set_body_force(BodyForce force) {
  body_force_ = std::move(force);
  built_ = false;
}

void ExternalLoadsTerm::build() {
  const Discretisation::Cells& c = d_.cells();
  external_.reinit(d_.n_dofs());
  FEValues<3> values(*d_.mapping, *d_.fe, *d_.quadrature, update_values | update_JxW_values | update_quadrature_points);
  FEFaceValues<3> face_values(*d_.mapping, *d_.fe, *d_.face_quadrature, update_values | update_JxW_values);
  std::vector<types::global_dof_index> local(c.n);
  Vector<double> cell_external(c.n);
  for (const auto& cell : d_.dof.active_cell_iterators()) {
    cell_external = 0;
    if (body_force_) {
      values.reinit(cell);
      for (unsigned int q = 0; q < c.nq; ++q) {
        const Tensor<1, 3> f = body_force_(values.quadrature_point(q), cell->material_id());
        for (unsigned int i = 0; i < c.n; ++i)
          cell_external(i) += f[c.component[i]] * values.shape_value_component(i, q, c.component[i]) * values.JxW(q);
      }
    }
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      for (const Traction& t : tractions_) {
        if (cell->face(f)->boundary_id() != t.boundary) continue;
        face_values.reinit(cell, f);
        for (unsigned int q = 0; q < d_.face_quadrature->size(); ++q)
          for (unsigned int i = 0; i < c.n; ++i)
            cell_external(i) += t.value[c.component[i]] * face_values.shape_value_component(i, q, c.component[i]) *
                                face_values.JxW(q);
      }
    }
    cell->get_dof_indices(local);
    external_.add(local, cell_external);
  }
  built_ = true;
}

bool ExternalLoadsTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  if (!built_) build();
  const double factor = state.static_factor;
  for (types::global_dof_index i = 0; i < external_.size(); ++i) {
    target.residual[i] += factor * external_[i];
    if (target.internal) target.internal[i] -= factor * external_[i];
  }
  return true;
}

}  // namespace fetouch::fem
