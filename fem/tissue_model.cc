#include "fem/tissue_model.h"

#include <atomic>
#include <cmath>
#include <stdexcept>

#include "fem/physical_problem.h"
#include "fem/tissue_mesh_builder.h"

namespace fetouch::fem {

namespace {

std::atomic<long> gravity_counter{0};

bool selects(const config::Selector& s, const dealii::Point<3>& c) {
  switch (s.kind) {
    case config::SelectorKind::box:
      for (int d = 0; d < 3; ++d)
        if (c[d] < s.box_min[d] - 1e-12 || c[d] > s.box_max[d] + 1e-12) return false;
      return true;
    case config::SelectorKind::plane: {
      const double n = std::sqrt(s.plane_normal[0] * s.plane_normal[0] + s.plane_normal[1] * s.plane_normal[1] +
                                 s.plane_normal[2] * s.plane_normal[2]);
      double distance = 0;
      for (int d = 0; d < 3; ++d) distance += (c[d] - s.plane_point[d]) * s.plane_normal[d] / n;
      return std::abs(distance) <= s.plane_tolerance_m;
    }
    case config::SelectorKind::physical_group: return false;
  }
  return false;
}

// A piece of tissue that its supports leave free to move rigidly has no equilibrium under a probe's
// force or its weight: the solve fails, or the piece floats away from the probe and the force felt
// is zero. Said before anything runs, with what to change.
void require_held(TissueModel& model) {
  const std::vector<Discretisation::Piece> pieces = model.solver->pieces();
  model.pieces = static_cast<unsigned int>(pieces.size());
  std::string problem;
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const std::vector<std::string>& free = pieces[p].free_motions;
    if (free.empty()) continue;
    std::string what = pieces.size() == 1 ? "the tissue" : "piece " + std::to_string(p + 1) + " of the " +
                                                               std::to_string(pieces.size()) + " the mesh falls into (" +
                                                               std::to_string(pieces[p].cells) + " cells)";
    if (free.size() == 6) {
      what += " is not held: no fixed, symmetry or roller boundary region reaches it";
    } else {
      what += " is not held against ";
      for (std::size_t k = 0; k < free.size(); ++k) what += (k == 0 ? "" : k + 1 == free.size() ? " and " : ", ") + free[k];
    }
    problem += (problem.empty() ? "" : "; ") + what;
  }
  if (problem.empty()) return;
  throw PhysicalProblem(problem + " (a probe would push it away, so no force could be felt): hold part of its boundary "
                        "with a `boundary:` region of type fixed (or components that stop those motions)" +
                        (pieces.size() > 1 ? std::string(", or mesh the tissue as one piece") : std::string()));
}

}  // namespace

long gravity_evaluations() { return gravity_counter.load(std::memory_order_relaxed); }

std::unique_ptr<TissueModel> build_tissue_model(const config::Scene& scene,
                                                const std::function<void(dealii::Triangulation<3>&)>& adjust) {
  auto model = std::make_unique<TissueModel>();
  model->mesh = build_tissue_mesh(scene.mesh, model->triangulation);
  model->material = make_material(scene.material);
  const RegionMaterials assigned = assign_region_materials(scene, model->mesh);
  if (!assigned.problems.empty()) {
    std::string message;
    for (const config::Diagnostic& d : assigned.problems)
      message += (message.empty() ? "" : "; ") + d.key + " (line " + std::to_string(d.line) + "): " + d.message;
    throw std::runtime_error(message);
  }
  for (const auto& [id, index] : assigned.of_region) {
    const config::Material& m = index < 0 ? scene.material : scene.materials[static_cast<std::size_t>(index)].material;
    model->region_density_kg_per_m3[id] = m.density_kg_per_m3;
    if (index >= 0) model->region_materials[id] = make_material(m);
  }
  model->degree = scene.mesh.element == config::ElementType::p2 || scene.mesh.element == config::ElementType::q2 ? 2 : 1;

  // Boundary ids for box and plane selectors, above every id the mesh uses.
  unsigned int next_id = 100;
  for (const auto& [name, id] : model->mesh.boundary_ids) next_id = std::max(next_id, id + 1);
  for (const config::BoundaryRegion& region : scene.boundary) {
    unsigned int id;
    unsigned int faces = 0;
    if (region.select.kind == config::SelectorKind::physical_group) {
      const auto found = model->mesh.boundary_ids.find(region.select.physical_group);
      if (found == model->mesh.boundary_ids.end())
        throw std::runtime_error("boundary region " + region.name + ": the mesh has no physical group " +
                                 region.select.physical_group);
      id = found->second;
      for (const auto& cell : model->triangulation.active_cell_iterators())
        for (const unsigned int f : cell->face_indices()) faces += cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == id;
    } else {
      id = next_id++;
      for (const auto& cell : model->triangulation.active_cell_iterators())
        for (const unsigned int f : cell->face_indices())
          if (cell->face(f)->at_boundary() && selects(region.select, cell->face(f)->center())) {
            cell->face(f)->set_boundary_id(id);
            ++faces;
          }
    }
    if (faces == 0)
      throw std::runtime_error("boundary region " + region.name + " (line " + std::to_string(region.where.line) +
                               "): its selector selects no boundary face of the mesh");
    model->region_ids[region.name] = id;
    model->region_faces[region.name] = faces;
  }

  if (adjust) adjust(model->triangulation);
  model->solver = std::make_unique<QuasiStaticSolver>(model->triangulation, *model->material, model->degree);
  for (const auto& [id, material] : model->region_materials) model->solver->set_region_material(id, *material);
  // The linear solver: CG on a stale factorisation, or CG with algebraic multigrid past the size
  // where factorising costs too much (solver.direct_max_dofs) or when the scene asks for it.
  const bool amg = scene.solver.linear_solver == config::LinearSolver::cg_amg ||
                   (scene.solver.linear_solver == config::LinearSolver::automatic &&
                    model->solver->dofs() > static_cast<unsigned int>(scene.solver.direct_max_dofs));
  model->solver->use_algebraic_multigrid(amg);
  for (const config::BoundaryRegion& region : scene.boundary) {
    const unsigned int id = model->region_ids.at(region.name);
    if (region.type != config::BoundaryType::traction) {  // fixed, symmetry, roller: u = 0 on its components
      model->solver->prescribe_displacement(id, region.components, dealii::Tensor<1, 3>());
    } else {
      dealii::Tensor<1, 3> t;
      for (int d = 0; d < 3; ++d) t[d] = region.traction_pa[d];
      model->solver->apply_traction(id, t);
    }
  }
  if (scene.effects.has(config::Effect::gravity)) {  // rho g, rho of each region
    dealii::Tensor<1, 3> g;
    for (int d = 0; d < 3; ++d) g[d] = scene.effects.gravity_m_per_s2[d];
    model->solver->apply_body_force(
        [g, density = model->region_density_kg_per_m3](const dealii::Point<3>&, unsigned int id) {
          gravity_counter.fetch_add(1, std::memory_order_relaxed);
          const auto rho = density.find(id);
          return rho == density.end() ? dealii::Tensor<1, 3>() : rho->second * g;
        });
  }
  if (scene.effects.has(config::Effect::cavity)) {
    CavityLaw law;
    law.gas = scene.effects.cavity_law == config::PressureVolumeLaw::isothermal_gas;
    law.initial_pressure_pa = scene.effects.cavity_initial_pressure_pa;
    law.bulk_modulus_pa = scene.effects.cavity_bulk_modulus_pa;
    const bool by_regions = !scene.effects.cavity_regions.empty();
    const std::string what = by_regions ? "the regions it holds" : scene.effects.cavity_surface;
    try {
      if (by_regions) {
        std::set<unsigned int> contents;
        for (const std::string& name : scene.effects.cavity_regions) {
          const auto region = find_region(model->mesh, name);
          if (!region) throw std::runtime_error("effect cavity: the mesh has no volume region " + name);
          contents.insert(region->material_id);
        }
        model->solver->add_cavity(contents, law);
      } else {
        const auto found = model->mesh.boundary_ids.find(scene.effects.cavity_surface);
        if (found == model->mesh.boundary_ids.end())
          throw std::runtime_error("effect cavity: the mesh has no physical group " + scene.effects.cavity_surface);
        model->solver->add_cavity(found->second, law);
      }
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error("effect cavity on " + what + ": " + e.what());
    }
  }
  if (scene.effects.has(config::Effect::incompressibility)) {
    // The mean-dilatation formulation; a coupled material has no volumetric part to take per cell
    // (the scene loader warned), and keeps the displacement formulation.
    double u1 = 0, u2 = 0;
    bool decoupled = model->material->volumetric(1.0, u1, u2);
    for (const auto& [id, material] : model->region_materials) decoupled = decoupled && material->volumetric(1.0, u1, u2);
    if (decoupled) model->solver->use_mean_dilatation(true);
  }
  model->newton.relative_tolerance = scene.solver.newton_relative_tolerance;
  model->newton.absolute_tolerance = scene.solver.newton_absolute_tolerance;
  model->newton.max_iterations = scene.solver.newton_max_iterations;
  model->newton.max_cuts = scene.solver.max_load_step_cuts;
  model->newton.line_search = scene.solver.line_search;
  model->newton.position_tolerance_m = scene.solver.accuracy_position_m;
  model->newton.force_tolerance_n = scene.solver.accuracy_force_n;
  model->newton.frame_iterations = scene.solver.frame_newton_iterations;
  model->solver->set_compliance_accuracy(scene.solver.accuracy_compliance);
  require_held(*model);
  return model;
}

std::optional<QuasiStaticSolver::Dynamics> scene_dynamics(const config::Scene& scene, const TissueModel* model) {
  const bool damping = scene.effects.has(config::Effect::damping);
  if (!scene.effects.has(config::Effect::inertia)) {
    if (damping) throw std::runtime_error("effect damping needs effect inertia (Rayleigh damping acts on the motion)");
    return std::nullopt;
  }
  QuasiStaticSolver::Dynamics d;
  d.density_kg_per_m3 = scene.material.density_kg_per_m3;
  if (model) d.region_density_kg_per_m3 = model->region_density_kg_per_m3;
  d.time_step_s = 1.0 / scene.solver.rate_hz;
  switch (scene.effects.integrator) {
    case config::TimeIntegrator::newmark: d.newmark = true; break;
    case config::TimeIntegrator::backward_euler: d.newmark = false; break;
    case config::TimeIntegrator::hht: {
      const Dynamics hht = Dynamics::hht(scene.effects.hht_alpha);
      d.newmark = true, d.hht_alpha = hht.hht_alpha, d.beta = hht.beta, d.gamma = hht.gamma;
      break;
    }
  }
  if (damping) {
    d.rayleigh_mass_per_s = scene.effects.rayleigh_mass_per_s;
    d.rayleigh_stiffness_s = scene.effects.rayleigh_stiffness_s;
  }
  return d;
}

}  // namespace fetouch::fem
