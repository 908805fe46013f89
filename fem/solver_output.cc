// Post-processing and output of a QuasiStaticSolver's state: per-cell fields (J, von Mises stress),
// point values and error norms against exact solutions, and the deformed body as VTU (or per-rank
// pieces gathered by a PVTU) for ParaView.
#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/numerics/data_component_interpretation.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools.h>

#include <cmath>
#include <fstream>
#include <map>
#include <stdexcept>

#include "fem/quasi_static_solver.h"
#include "fem/solver_parts.h"

namespace fetouch::fem {

using namespace dealii;

namespace {

// The deformed state as DataOut patches: displacement (dof data), J and von Mises stress (cell data),
// optionally on the cells of one rank only.
struct Output {
  DataOut<3> out;
  Vector<double> jacobian, von_mises;
};

void fill_output(const QuasiStaticSolver::Impl& m, const QuasiStaticSolver::CellFields& fields, Output& o,
                 bool own_cells_only) {
  o.out.attach_dof_handler(m.d.dof);
  const std::vector<std::string> names(3, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> kinds(
      3, DataComponentInterpretation::component_is_part_of_vector);
  o.out.add_data_vector(m.u, names, DataOut<3>::type_dof_data, kinds);
  o.jacobian = Vector<double>(fields.jacobian.begin(), fields.jacobian.end());
  o.von_mises = Vector<double>(fields.von_mises.begin(), fields.von_mises.end());
  o.out.add_data_vector(o.jacobian, "J", DataOut<3>::type_cell_data);
  o.out.add_data_vector(o.von_mises, "von_mises_stress_pa", DataOut<3>::type_cell_data);
  if (own_cells_only)
    o.out.set_cell_selection([&m](const typename Triangulation<3>::cell_iterator& cell) {
      return cell->is_active() && m.d.cell_rank[cell->active_cell_index()] == static_cast<unsigned int>(m.d.rank);
    });
  o.out.build_patches(*m.d.mapping, m.d.fe->degree);
}

}  // namespace

// Each rank's own cells (the per-cell data it keeps), gathered onto every rank in cell order.
QuasiStaticSolver::CellFields QuasiStaticSolver::cell_fields() const {
  const Impl& m = *impl_;
  const Discretisation& d = m.d;
  const Discretisation::Cells& c = d.cells();
  const unsigned int nq = c.nq;
  std::vector<double> mine;  // [slot][jacobian, von Mises]
  mine.reserve(2 * d.my_cells.size());
  std::vector<double> u_local(c.n);
  for (const unsigned int k : d.my_cells) {
    d.gather(k, m.u, u_local.data());
    double j_sum = 0, vm_sum = 0;
    for (unsigned int q = 0; q < nq; ++q) {
      const Tensor2 F = d.deformation_gradient(k, q, u_local.data());
      const double j = determinant(F);
      j_sum += j;
      Tensor2 P;
      if (j > 0 && m.elasticity.material_of(k).evaluate(F, P, nullptr)) {
        const Tensor<2, 3> sigma = P * transpose(F) / j;  // Cauchy
        const Tensor<2, 3> dev = sigma - trace(sigma) / 3 * unit_symmetric_tensor<3>();
        vm_sum += std::sqrt(1.5 * scalar_product(dev, dev));
      }
    }
    mine.push_back(j_sum / nq);
    mine.push_back(vm_sum / nq);
  }
  std::vector<double> all;
  std::vector<int> start(d.ranks + 1, 0);
  if (d.ranks == 1) {
    all = std::move(mine);
  } else {
    std::vector<int> counts(d.ranks);
    const int count = static_cast<int>(mine.size());
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, d.comm);
    for (int r = 0; r < d.ranks; ++r) start[r + 1] = start[r] + counts[r];
    all.resize(start[d.ranks]);
    MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), start.data(), MPI_DOUBLE, d.comm);
  }
  const unsigned int cells = d.n_cells();
  CellFields fields;
  fields.jacobian.resize(cells);
  fields.von_mises.resize(cells);
  std::vector<int> next(start.begin(), start.end() - 1);  // each rank's next cell among its own
  for (unsigned int k = 0; k < cells; ++k) {
    int& at = next[d.ranks == 1 ? 0 : d.cell_rank[k]];
    fields.jacobian[k] = all[at];
    fields.von_mises[k] = all[at + 1];
    at += 2;
  }
  return fields;
}

double QuasiStaticSolver::max_displacement() const {
  const Impl& m = *impl_;
  std::vector<types::global_dof_index> indices(m.d.fe->n_dofs_per_cell());
  double worst = 0;
  for (const auto& cell : m.d.dof.active_cell_iterators()) {
    cell->get_dof_indices(indices);
    for (unsigned int node = 0; node < m.d.fe->base_element(0).n_dofs_per_cell(); ++node) {
      Tensor<1, 3> u;
      for (unsigned int c = 0; c < 3; ++c) u[c] = m.u[indices[m.d.fe->component_to_system_index(c, node)]];
      worst = std::max(worst, u.norm());
    }
  }
  return worst;
}

QuasiStaticSolver::DrawingMesh QuasiStaticSolver::drawing_mesh() const {
  const Impl& m = *impl_;
  DrawingMesh mesh;
  mesh.points.reserve(m.d.tria.n_vertices());
  for (const Point<3>& p : m.d.tria.get_vertices()) mesh.points.push_back({p[0], p[1], p[2]});
  // deal.II's hexahedron numbers its vertices lexicographically: the six tetrahedra around the
  // 0-7 diagonal, each through two neighbouring corners of the ring 1-3-2-6-4-5.
  static constexpr unsigned int kRing[6] = {1, 3, 2, 6, 4, 5};
  for (const auto& cell : m.d.tria.active_cell_iterators()) {
    const unsigned int index = cell->active_cell_index(), id = cell->material_id();
    if (cell->n_vertices() == 4) {
      mesh.tetrahedra.push_back({cell->vertex_index(0), cell->vertex_index(1), cell->vertex_index(2), cell->vertex_index(3)});
      mesh.tetrahedron_cell.push_back(index), mesh.material.push_back(id);
    } else {
      for (unsigned int r = 0; r < 6; ++r) {
        mesh.tetrahedra.push_back({cell->vertex_index(0), cell->vertex_index(kRing[r]), cell->vertex_index(kRing[(r + 1) % 6]),
                                   cell->vertex_index(7)});
        mesh.tetrahedron_cell.push_back(index), mesh.material.push_back(id);
      }
    }
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const auto face = cell->face(f);
      if (face->n_vertices() == 3) {
        mesh.boundary_triangles.push_back({face->vertex_index(0), face->vertex_index(1), face->vertex_index(2)});
        mesh.boundary_triangle_cell.push_back(index);
      } else {  // a quadrilateral's vertices are numbered 0 1 / 2 3
        mesh.boundary_triangles.push_back({face->vertex_index(0), face->vertex_index(1), face->vertex_index(3)});
        mesh.boundary_triangles.push_back({face->vertex_index(0), face->vertex_index(3), face->vertex_index(2)});
        mesh.boundary_triangle_cell.insert(mesh.boundary_triangle_cell.end(), 2, index);
      }
    }
  }
  return mesh;
}

void QuasiStaticSolver::vertex_displacements(std::vector<float>& out) const {
  const Impl& m = *impl_;
  const std::size_t size = 3 * m.d.tria.n_vertices();
  if (out.size() != size) out.assign(size, 0.0f);
  std::vector<types::global_dof_index> indices(m.d.fe->n_dofs_per_cell());
  for (const auto& cell : m.d.dof.active_cell_iterators()) {
    cell->get_dof_indices(indices);
    for (unsigned int v = 0; v < cell->n_vertices(); ++v)
      for (unsigned int c = 0; c < 3; ++c)
        out[3 * cell->vertex_index(v) + c] = static_cast<float>(m.u[indices[m.d.fe->component_to_system_index(c, v)]]);
  }
}

Tensor<1, 3> QuasiStaticSolver::displacement_at(const Point<3>& point) const {
  Vector<double> value(3);
  VectorTools::point_value(*impl_->d.mapping, impl_->d.dof, impl_->u, point, value);
  Tensor<1, 3> t;
  for (int c = 0; c < 3; ++c) t[c] = value[c];
  return t;
}

double QuasiStaticSolver::max_nodal_error(const std::function<Tensor<1, 3>(const Point<3>&)>& exact) const {
  std::map<types::global_dof_index, Point<3>> points;
  DoFTools::map_dofs_to_support_points(*impl_->d.mapping, impl_->d.dof, points);
  double worst = 0;
  const std::vector<int> component = impl_->d.dof_components();
  for (const auto& [index, point] : points) worst = std::max(worst, std::abs(impl_->u[index] - exact(point)[component[index]]));
  return worst;
}

double QuasiStaticSolver::l2_error(const std::function<Tensor<1, 3>(const Point<3>&)>& exact) const {
  const Impl& m = *impl_;
  const ScaledField field(exact, 1.0);
  Vector<float> per_cell(m.d.n_cells());
  const unsigned int order = m.d.fe->degree + 2;  // Gauss quadrature two orders above the element's
  std::unique_ptr<Quadrature<3>> q;
  if (m.d.simplex)
    q = std::make_unique<QGaussSimplex<3>>(order);
  else
    q = std::make_unique<QGauss<3>>(order);
  VectorTools::integrate_difference(*m.d.mapping, m.d.dof, m.u, field, per_cell, *q, VectorTools::L2_norm);
  return VectorTools::compute_global_error(m.d.tria, per_cell, VectorTools::L2_norm);
}

void QuasiStaticSolver::write_vtu(const std::string& path) const {
  Output o;
  fill_output(*impl_, cell_fields(), o, false);
  std::ofstream file(path);
  if (!file) throw std::runtime_error("cannot write " + path);
  o.out.write_vtu(file);
  if (!file) throw std::runtime_error("cannot write " + path);
}

std::string QuasiStaticSolver::write_vtu_pieces(const std::string& directory, const std::string& name,
                                                unsigned int counter) const {
  Output o;
  fill_output(*impl_, cell_fields(), o, true);
  try {
    return o.out.write_vtu_with_pvtu_record(directory + "/", name, counter, impl_->d.comm, 4);
  } catch (const std::exception&) {
    throw std::runtime_error("cannot write " + directory + "/" + name + " (parallel VTU pieces)");
  }
}

}  // namespace fetouch::fem
