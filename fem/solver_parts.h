// What a QuasiStaticSolver is made of (internal to fem/: quasi_static_solver.cc composes the parts,
// solver_output.cc reads them). Each effect is a term, built only when asked for.
#pragma once

#include <deal.II/lac/vector.h>

#include <memory>
#include <vector>

#include "fem/cavity_term.h"
#include "fem/condensed_compliance.h"
#include "fem/contact_patches.h"
#include "fem/discretisation.h"
#include "fem/elasticity_term.h"
#include "fem/external_loads.h"
#include "fem/inertia_term.h"
#include "fem/linear_system.h"
#include "fem/newton_driver.h"
#include "fem/quasi_static_solver.h"

namespace fetouch::fem {

struct QuasiStaticSolver::Impl {
  Impl(const dealii::Triangulation<3>& t, const Material& m, int degree, MPI_Comm comm)
      : d(t, degree, comm), system(d, comm), u(d.n_dofs()), driver(d, system, supports, u), elasticity(d, m) {
    update_terms();
  }

  Discretisation d;
  LinearSystem system;
  std::vector<Support> supports;
  dealii::Vector<double> u;
  NewtonDriver driver;

  // The terms; null when the scene or the caller did not ask for the effect.
  ElasticityTerm elasticity;
  std::unique_ptr<InertiaTerm> inertia;
  std::unique_ptr<StiffnessDampingTerm> damping;  // made by the first solve (needs K0)
  std::unique_ptr<CavityTerm> cavity;
  std::unique_ptr<ExternalLoadsTerm> loads;
  std::unique_ptr<ContactPatchesTerm> patches;

  CondensedCompliance compliance;
  ComplianceTimes compliance_times;
  TangentSystem::Method method = TangentSystem::Method::factorisation;
  bool set_up = false;  // constraints and sparsity for the current supports

  // The driver's list, in assembly order: the cell terms, then the global ones.
  void update_terms() {
    std::vector<Term*> terms{&elasticity};
    for (Term* t : std::initializer_list<Term*>{inertia.get(), damping.get(), cavity.get(), loads.get(), patches.get()})
      if (t) terms.push_back(t);
    driver.set_terms(terms);
  }
  void ensure_set_up() {
    if (set_up) return;
    system.set_up(supports, method);
    set_up = true;
    driver.invalidate_tangent(/*values_lost=*/true);
    compliance.clear();
  }
};

}  // namespace fetouch::fem
