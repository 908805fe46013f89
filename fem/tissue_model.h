// A scene's tissue as the solver sees it: the triangulation, the material and a QuasiStaticSolver
// with the scene's boundary regions (fixed, traction) and effects that apply to a static solve
// (gravity). Selectors: a physical group names the mesh's own boundary region; a box or a plane
// selects the boundary faces whose centres lie inside it (they get a boundary id of their own).
#pragma once

#include <deal.II/grid/tria.h>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/scene.h"
#include "fem/material.h"
#include "fem/quasi_static_solver.h"
#include "fem/tissue_mesh.h"

namespace fetouch::fem {

struct TissueModel {
  dealii::Triangulation<3> triangulation;
  TissueMeshInfo mesh;
  std::unique_ptr<Material> material;  // the body's: the scene's `material`, or its first region's
  std::map<unsigned int, std::unique_ptr<Material>> region_materials;  // by material id, from `materials`
  std::map<unsigned int, double> region_density_kg_per_m3;            // every region's
  std::unique_ptr<QuasiStaticSolver> solver;
  std::map<std::string, unsigned int> region_ids;  // scene boundary region -> boundary id
  std::map<std::string, unsigned int> region_faces;  // scene boundary region -> faces selected
  NewtonSettings newton;
  int degree = 1;
  unsigned int pieces = 1;  // the mesh's separate pieces (cells joined through vertices), each held
};

// Throws std::runtime_error naming the region when a selector selects no face, and at the scene's
// file and line when `materials` names a region the mesh lacks or leaves a region without one;
// PhysicalProblem (physical_problem.h) when a piece of the tissue is not held by its supports.
// `adjust`, if given, changes the triangulation after the scene's boundary regions have their ids
// and before the solver is built on it (a study's distorted mesh, its own material or boundary ids).
std::unique_ptr<TissueModel> build_tissue_model(const config::Scene& scene,
                                                const std::function<void(dealii::Triangulation<3>&)>& adjust = {});

// How many times the gravity of any scene has been evaluated (its body force at a point), over the
// process: a scene that does not list gravity runs no gravity code, and this shows it.
long gravity_evaluations();

// The time stepping a scene asks for (effects inertia and damping; one step per solver frame), or
// nothing for a quasi-static scene (Newmark, backward Euler or HHT-alpha, inertia_term.h). Throws
// std::runtime_error for damping without inertia.
// `model`: the densities of its regions (the scene's `material` density elsewhere).
std::optional<QuasiStaticSolver::Dynamics> scene_dynamics(const config::Scene& scene, const TissueModel* model = nullptr);

}  // namespace fetouch::fem
