#include "fem/quasi_static_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/component_mask.h>

#include "fem/boundary_geometry.h"
#include "fem/solver_parts.h"
#include "fem/stopwatch.h"

namespace fetouch::fem {

using namespace dealii;

std::string describe_frame(const SolveReport& r, const ComplianceTimes& c) {
  char line[480], kept[200] = "";
  const auto append = [&kept](const char* format, auto... values) {
    const std::size_t used = std::strlen(kept);
    std::snprintf(kept + used, sizeof kept - used, format, values...);
  };
  const auto plural = [](int count) { return count == 1 ? "" : "s"; };
  if (c.recycled_directions > 0 || c.carrier_kept)
    append(", kept %d directions%s", c.recycled_directions, c.carrier_kept ? " and the carrier" : "");
  if (c.first_residual != c.galerkin_residual)  // the old columns alone did not do: where they left it
    append(", old columns alone %.1e", c.first_residual);
  if (c.products > 0) append(", %d product%s with K %.1f ms", c.products, plural(c.products), 1e3 * c.products_s);
  if (c.rounds > 0)
    append(", %d round%s added %d direction%s", c.rounds, plural(c.rounds), c.new_directions, plural(c.new_directions));
  std::snprintf(line, sizeof line,
                "newton %d%s (%.1f ms: assembly %.1f, factor %.1f, solve %.1f ms, cg %d); compliance (%.1f ms: assembly "
                "%.1f, factor %.1f, solve %.1f ms, cg %d, galerkin %.1e%s%s)",
                r.total_iterations, r.carried ? " carried" : "", 1e3 * r.total_s, 1e3 * r.assembly_s,
                1e3 * r.factorisation_s, 1e3 * r.solve_s, r.linear_iterations, 1e3 * c.total_s, 1e3 * c.assembly_s,
                1e3 * c.factorisation_s, 1e3 * c.solves_s, c.linear_iterations, c.galerkin_residual, kept,
                c.refined ? ", solved" : "");
  std::string text = line;
  // The background factorisation: one taken up at the start (and how long the frame waited for
  // it), or one still being made (the worker shares the machine with this frame).
  if (r.background_taken) {
    std::snprintf(line, sizeof line, "; background factorisation taken up (waited %.1f ms)", 1e3 * r.background_wait_s);
    text += line;
  } else if (r.background_late) {
    text += "; background factorisation due and not ready (real time goes on without it)";
  } else if (r.background) {
    text += "; background factorisation under way";
  }
  if (!r.terms.empty()) {  // where the assembly went, per term (and a term's own solves)
    text += "; terms";
    for (const SolveReport::TermTime& t : r.terms) {
      std::snprintf(line, sizeof line, " %s %.1f", t.name.c_str(), 1e3 * t.assembly_s);
      text += line;
      if (t.other_s >= 5e-5) {
        std::snprintf(line, sizeof line, " (+%.1f own solves)", 1e3 * t.other_s);
        text += line;
      }
    }
  }
  return text;
}

QuasiStaticSolver::QuasiStaticSolver(const Triangulation<3>& triangulation, const Material& material, int degree,
                                     MPI_Comm comm)
    : impl_(std::make_unique<Impl>(triangulation, material, degree, comm)) {}

QuasiStaticSolver::~QuasiStaticSolver() = default;
QuasiStaticSolver::QuasiStaticSolver(QuasiStaticSolver&&) noexcept = default;
QuasiStaticSolver& QuasiStaticSolver::operator=(QuasiStaticSolver&&) noexcept = default;

int QuasiStaticSolver::ranks() const { return impl_->d.ranks; }
std::vector<Discretisation::Piece> QuasiStaticSolver::pieces() {
  impl_->ensure_set_up();
  return impl_->d.pieces(impl_->system.constrained());
}

unsigned int QuasiStaticSolver::dofs() const { return impl_->d.n_dofs(); }
unsigned int QuasiStaticSolver::cells() const { return impl_->d.n_cells(); }

std::vector<QuasiStaticSolver::Share> QuasiStaticSolver::shares() const {
  const Discretisation& d = impl_->d;
  const unsigned int mine[2] = {static_cast<unsigned int>(d.my_cells.size()),
                                static_cast<unsigned int>(d.owned_end - d.owned_begin)};
  std::vector<unsigned int> all(2 * std::size_t(d.ranks));
  if (d.ranks == 1) std::copy(mine, mine + 2, all.begin());
  else MPI_Allgather(mine, 2, MPI_UNSIGNED, all.data(), 2, MPI_UNSIGNED, d.comm);
  std::vector<Share> shares(d.ranks);
  for (int r = 0; r < d.ranks; ++r) shares[r] = {all[2 * r], all[2 * r + 1]};
  return shares;
}

std::vector<std::string> QuasiStaticSolver::terms() const {
  std::vector<std::string> names;
  for (const Term* term : impl_->driver.terms()) names.emplace_back(term->name());
  return names;
}

void QuasiStaticSolver::set_deterministic_factorisations(bool on) { impl_->system.tangent().set_deterministic(on); }
int QuasiStaticSolver::late_background_frames() const { return impl_->system.tangent().late_background_frames(); }
std::vector<TangentSystem::Level> QuasiStaticSolver::multigrid_levels() const {
  return impl_->system.tangent().multigrid_levels();
}

void QuasiStaticSolver::use_algebraic_multigrid(bool on) {
  impl_->method = on ? TangentSystem::Method::amg : TangentSystem::Method::factorisation;
  impl_->set_up = false;
}

void QuasiStaticSolver::set_assembly_threads(unsigned int threads) { impl_->elasticity.set_threads(threads); }

// ---- supports and loads -------------------------------------------------------------------------

void QuasiStaticSolver::prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                                               const Tensor<1, 3>& value) {
  prescribe_displacement(boundary_id, components, [value](const Point<3>&) { return value; });
}

void QuasiStaticSolver::prescribe_displacement(unsigned int boundary_id, std::array<bool, 3> components,
                                               std::function<Tensor<1, 3>(const Point<3>&)> field) {
  impl_->supports.push_back({boundary_id, components, std::move(field)});
  impl_->set_up = false;
}

namespace {

ExternalLoadsTerm& loads(QuasiStaticSolver::Impl& m) {
  if (!m.loads) {
    m.loads = std::make_unique<ExternalLoadsTerm>(m.d);
    m.update_terms();
  }
  return *m.loads;
}

}  // namespace

void QuasiStaticSolver::apply_traction(unsigned int boundary_id, const Tensor<1, 3>& traction) {
  loads(*impl_).add_traction(boundary_id, traction);
}

void QuasiStaticSolver::apply_body_force(std::function<Tensor<1, 3>(const Point<3>&)> force) {
  loads(*impl_).set_body_force([force](const Point<3>& x, unsigned int) { return force(x); });
}

void QuasiStaticSolver::apply_body_force(std::function<Tensor<1, 3>(const Point<3>&, unsigned int)> force) {
  loads(*impl_).set_body_force(std::move(force));
}

// ---- materials and effects ----------------------------------------------------------------------

void QuasiStaticSolver::set_region_material(unsigned int material_id, const Material& material) {
  impl_->elasticity.set_region_material(material_id, material);
}

void QuasiStaticSolver::use_mean_dilatation(bool on) { impl_->elasticity.use_mean_dilatation(on); }

void QuasiStaticSolver::enable_dynamics(const Dynamics& dynamics) {
  if (!(dynamics.time_step_s > 0) || !(dynamics.density_kg_per_m3 > 0))
    throw std::invalid_argument("dynamics: the time step and the density must be positive");
  if (dynamics.rayleigh_mass_per_s < 0 || dynamics.rayleigh_stiffness_s < 0)
    throw std::invalid_argument("dynamics: Rayleigh damping coefficients must not be negative");
  if (!(dynamics.hht_alpha >= -1.0 / 3.0 && dynamics.hht_alpha <= 0))
    throw std::invalid_argument("dynamics: HHT's alpha must lie in [-1/3, 0]");
  Impl& m = *impl_;
  m.inertia = std::make_unique<InertiaTerm>(m.d, dynamics);
  m.damping.reset();
  m.update_terms();
}

void QuasiStaticSolver::add_cavity(unsigned int boundary_id, const CavityLaw& law) {
  Impl& m = *impl_;
  if (m.cavity) throw std::invalid_argument("cavity: only one cavity per body");
  m.cavity = std::make_unique<CavityTerm>(m.d, boundary_id, law);
  m.update_terms();
}

void QuasiStaticSolver::add_cavity(const std::set<unsigned int>& contents, const CavityLaw& law) {
  Impl& m = *impl_;
  if (m.cavity) throw std::invalid_argument("cavity: only one cavity per body");
  m.cavity = std::make_unique<CavityTerm>(m.d, contents, law);
  m.update_terms();
}

double QuasiStaticSolver::cavity_volume() const { return impl_->cavity ? impl_->cavity->volume(impl_->u) : 0.0; }
double QuasiStaticSolver::cavity_reference_volume() const { return impl_->cavity ? impl_->cavity->reference_volume() : 0.0; }
double QuasiStaticSolver::cavity_pressure() const { return impl_->cavity ? impl_->cavity->pressure() : 0.0; }

// ---- contact patches ----------------------------------------------------------------------------

int QuasiStaticSolver::add_contact_patch(const Point<3>& center, double radius) {
  Impl& m = *impl_;
  auto made = m.patches ? nullptr : std::make_unique<ContactPatchesTerm>(m.d);
  ContactPatchesTerm& patches = m.patches ? *m.patches : *made;
  const int index = patches.add(center, radius);
  if (made) {
    m.patches = std::move(made);
    m.update_terms();
  }
  return index;
}

void QuasiStaticSolver::set_patch_force(int patch, const Tensor<1, 3>& force) { impl_->patches->set_force(patch, force); }
void QuasiStaticSolver::move_contact_patch(int patch, const Point<3>& center) { impl_->patches->move(patch, center); }
int QuasiStaticSolver::patches() const { return impl_->patches ? impl_->patches->size() : 0; }
Point<3> QuasiStaticSolver::patch_center(int patch) const { return (*impl_->patches)[patch].center; }
double QuasiStaticSolver::patch_radius(int patch) const { return (*impl_->patches)[patch].radius; }
Tensor<1, 3> QuasiStaticSolver::patch_displacement(int patch) const { return impl_->patches->displacement(patch, impl_->u); }
Tensor<1, 3> QuasiStaticSolver::patch_normal(int patch) const { return impl_->patches->deformed_normal(patch, impl_->u); }

Point<3> QuasiStaticSolver::boundary_point_nearest(const Point<3>& x, bool deformed) const {
  return fem::boundary_point_nearest(impl_->d, x, deformed ? &impl_->u : nullptr);
}

// ---- solving ------------------------------------------------------------------------------------

SolveReport QuasiStaticSolver::solve(const NewtonSettings& s) {
  const auto started = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.ensure_set_up();
  // A solve that continues from a converged one (a haptic frame, a time step) never waits for a
  // factorisation: stale ones are replaced in the background.
  const bool background = m.system.tangent().background_under_way();
  const int factorisations_before = m.system.tangent().factorisations();
  const double waited = m.system.tangent().begin_frame(m.driver.loaded());
  const bool taken = m.system.tangent().factorisations() != factorisations_before;
  if (m.inertia && m.inertia->dynamics().rayleigh_stiffness_s != 0 && !m.damping) {
    // beta K0: the elastic tangent's values at the reference state, constrained diagonals zero.
    Vector<double> zero(m.d.n_dofs()), r(m.d.n_dofs());
    TangentSystem& k = m.system.tangent();
    k.zero();
    AssemblyTarget target{r.begin(), nullptr, k.values(), &m.system};
    if (!m.elasticity.assemble({zero, 0.0, 0.0}, target))
      throw std::runtime_error("stiffness damping: the reference state's tangent could not be assembled");
    m.d.sum_over_ranks(k.values(), k.nonzeros());
    m.damping = std::make_unique<StiffnessDampingTerm>(*m.inertia, std::vector<double>(k.values(), k.values() + k.nonzeros()));
    m.driver.invalidate_tangent(/*values_lost=*/true);  // the matrix held K0 without its supports' diagonal
    m.update_terms();
  }
  // A frame that changes only the patch forces starts from the linear prediction u + Z dF, Z = K^-1 H'
  // the last compliance's columns (at this state): a Newton step without assembly or solve. The
  // tolerance stays relative to the residual the force change makes at the old state, |H' dF|.
  NewtonDriver::Predictor predictor;
  const std::vector<Vector<double>>& z = m.compliance.columns();
  if (!m.inertia && m.driver.loaded() && s.load_steps <= 1 && m.patches && z.size() == 3 * std::size_t(m.patches->size()))
    predictor = [&m, &z](Vector<double>& u) {
      Vector<double> load(m.d.n_dofs());
      for (int a = 0; a < m.patches->size(); ++a)
        for (int c = 0; c < 3; ++c) {
          const auto& p = (*m.patches)[a];
          const double df = p.force[c] - p.converged_force[c];
          load.add(df, p.h[c]);
          u.add(df, z[3 * a + c]);
        }
      m.system.constraints().set_zero(load);
      return load.l2_norm();
    };
  // The accuracy policy's estimate: a residual r leaves a displacement error K^-1 r, of which the
  // contacts see H K^-1 r = Z'r (Z = K^-1 H', the compliance columns).
  NewtonDriver::HandoverError handover_error;
  if (m.patches && z.size() == 3 * std::size_t(m.patches->size()))
    handover_error = [&z](const Vector<double>& r) {
      double worst = 0;
      for (std::size_t a = 0; a < z.size() / 3; ++a) {
        Tensor<1, 3> e;
        for (int c = 0; c < 3; ++c) e[c] = z[3 * a + c] * r;
        worst = std::max(worst, e.norm());
      }
      return worst;
    };
  SolveReport report = m.driver.solve(s, predictor, handover_error);
  report.factorisation_s += waited;  // for a background factorisation taken up now
  report.background = background || m.system.tangent().background_under_way();
  report.background_taken = taken;
  report.background_wait_s = waited;
  report.background_late = m.system.tangent().background_late();
  const std::vector<Term*>& terms = m.driver.terms();
  for (std::size_t i = 0; i < terms.size() && i < m.driver.term_times.size(); ++i) {
    report.terms.push_back(m.driver.term_times[i]);
    report.terms.back().name = terms[i]->name();
  }
  report.total_s = seconds_since(started);
  return report;
}

FullMatrix<double> QuasiStaticSolver::compliance() {
  Impl& m = *impl_;
  m.ensure_set_up();
  const auto start = std::chrono::steady_clock::now();
  if (!m.driver.tangent_current()) {  // after a converged solve the tangent already is the current state's
    Vector<double> r(m.d.n_dofs());
    if (!m.driver.assemble(1.0, r, /*tangent=*/true)) throw std::runtime_error("compliance: an element is inverted");
  }
  m.compliance_times = ComplianceTimes();
  m.compliance_times.assembly_s = seconds_since(start);
  std::vector<Vector<double>> h;
  for (int a = 0; a < patches(); ++a)
    for (int c = 0; c < 3; ++c) {
      h.push_back((*m.patches)[a].h[c]);
      m.system.constraints().set_zero(h.back());
    }
  FullMatrix<double> w = m.compliance.compute(m.system, h, m.compliance_times);
  m.compliance_times.total_s = seconds_since(start);
  return w;
}

const ComplianceTimes& QuasiStaticSolver::last_compliance_times() const { return impl_->compliance_times; }

void QuasiStaticSolver::set_compliance_accuracy(double relative_error) {
  if (!(relative_error > 0 && relative_error < 1))
    throw std::invalid_argument("compliance accuracy: a relative error in (0, 1)");
  impl_->compliance.galerkin_tolerance = std::sqrt(relative_error);
}

Tensor<1, 3> QuasiStaticSolver::boundary_force(unsigned int boundary_id) const {
  Impl& m = *impl_;
  m.ensure_set_up();
  Vector<double> r(m.d.n_dofs()), internal(m.d.n_dofs());
  if (!m.driver.assemble(1.0, r, false, &internal)) throw std::runtime_error("boundary_force: an element is inverted");
  Tensor<1, 3> force;
  for (int c = 0; c < 3; ++c) {
    ComponentMask mask(3, false);
    mask.set(c, true);
    for (const auto i : DoFTools::extract_boundary_dofs(m.d.dof, mask, {types::boundary_id(boundary_id)})) force[c] += internal[i];
  }
  return force;
}

}  // namespace fetouch::fem
