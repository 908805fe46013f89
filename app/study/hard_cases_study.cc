// `fetouch study hard-cases`: the solver's hard cases on a scene's tissue (its mesh, materials and
// supports) or on a built-in block. Each case must end sound: converged with every element's J > 0
// and every field finite, or, where a case asks for it, failed cleanly: rolled back to the last
// converged state with a reason. The probe's place is the scene's first probe's contact patch (the
// block's top centre); "depth" is the tissue's extent along the axis nearest the inward normal there.
#include <deal.II/grid/grid_tools.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <sstream>

#include "app/log.h"
#include "app/progress.h"
#include "app/scene_mesh.h"
#include "app/scene_rig.h"
#include "app/study/hard_cases_report.h"
#include "app/study/study.h"
#include "fem/fem_environment.h"
#include "fem/material.h"
#include "fem/tissue_model.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;
using dealii::Point;
using dealii::Tensor;
using Adjust = std::function<void(dealii::Triangulation<3>&)>;

constexpr unsigned int kPressedFaces = 250;  // the compression's boundary id
constexpr unsigned int kStiffRegion = 250;   // the stiff layer's material id

// The block of the hard-case tests: 10 x 8 x 5 cm, P2 tetrahedra, soft neo-Hookean tissue on a table.
config::Scene builtin_block() {
  config::Scene s;
  s.name = "block", s.description = "the built-in hard-case block";
  s.mesh.source = config::MeshSource::generated;
  s.mesh.generated.shape = config::GeneratedShape::box;
  s.mesh.generated.size_m = {0.10, 0.08, 0.05};
  s.mesh.generated.refinements = 1;
  s.mesh.element = config::ElementType::p2;
  s.material.model = config::MaterialModel::neo_hookean;
  s.material.youngs_modulus_pa = 5000, s.material.poisson_ratio = 0.45, s.material.density_kg_per_m3 = 1050;
  s.effects.listed = {config::Effect::elasticity, config::Effect::contact};
  config::BoundaryRegion table;
  table.name = "table";
  table.select.kind = config::SelectorKind::physical_group;
  table.select.physical_group = "zmin";
  s.boundary.push_back(table);
  config::Probe probe;
  probe.name = "tool", probe.radius_m = 0.01;
  s.probes.push_back(probe);
  return s;
}

// Where the cases press: the patch point, the inward direction, the tissue's depth along its axis.
struct Site {
  Point<3> point;
  Tensor<1, 3> inward, tangent;
  int axis = 2;
  double depth = 0.05, radius = 0.01, lo = 0, hi = 0;  // the tissue's extent along the axis
  double force_n = 1.5;  // a firm press: the block's 1.5 N, a scene's half its device's peak force
};

class Battery {
 public:
  Battery(const config::Scene& scene, bool builtin, const HardCasesOptions& o) : scene_(scene), builtin_(builtin), o_(o) {
    settings_.max_cuts = o.max_cuts >= 0 ? o.max_cuts : 8;
    settings_.line_search = !o.no_line_search;
    // Where the probe touches, and the tissue's extent.
    auto model = build(scene_, {});
    const auto box = dealii::GridTools::compute_bounding_box(model->triangulation);
    Point<3> start(0.05, 0.04, 0.05);
    if (!builtin_) {
      const haptics::Trajectory path = probe_trajectory(scene_.probes.front(), 0);
      start = Point<3>(path.positions_m.front()[0], path.positions_m.front()[1], path.positions_m.front()[2]);
      site_.radius = scene_.probes.front().radius_m;
      site_.force_n = 0.5 * scene_.haptics.max_force_n;
    }
    site_.point = model->solver->boundary_point_nearest(start, false);
    const int patch = model->solver->add_contact_patch(site_.point, site_.radius);
    site_.inward = -model->solver->patch_normal(patch);
    for (int d = 0; d < 3; ++d)
      if (std::abs(site_.inward[d]) > std::abs(site_.inward[site_.axis])) site_.axis = d;
    site_.lo = box.lower_bound(site_.axis), site_.hi = box.upper_bound(site_.axis);
    site_.depth = site_.hi - site_.lo;
    Tensor<1, 3> other;
    other[(site_.axis + 1) % 3] = 1;
    site_.tangent = other - (other * site_.inward) * site_.inward;
    site_.tangent /= site_.tangent.norm();
  }
  const Site& site() const { return site_; }

  std::vector<std::function<HardCaseOutcome()>> cases();

 private:
  HardCaseOutcome through_environment(const std::string& name, double force, bool teleport);
  std::unique_ptr<fem::TissueModel> build(const config::Scene& scene, const Adjust& adjust) const {
    return fem::build_tissue_model(scene, adjust);
  }
  Tensor<1, 3> press(double newtons) const { return newtons * site_.inward; }
  // The soundness of the solver's state after a case: J > 0 everywhere, fields finite.
  static void inspect(const fem::QuasiStaticSolver& solver, HardCaseOutcome& o) {
    const auto fields = solver.cell_fields();
    o.min_j = fields.jacobian.empty() ? 0 : *std::min_element(fields.jacobian.begin(), fields.jacobian.end());
    o.finite = std::isfinite(solver.max_displacement()) && std::isfinite(o.min_j);
  }
  static void account(const fem::SolveReport& r, HardCaseOutcome& o) {
    o.iterations += std::max(0, r.total_iterations), o.cuts += r.cuts;
    if (!r.converged) ++o.rollbacks, o.failure = r.failure;
  }
  // The case must converge.
  static void must_converge(HardCaseOutcome& o) {
    o.expected = "converged";
    o.sound = o.converged && o.min_j > 0 && o.finite;
  }
  // A patch force applied in `steps` solves (each continuing from the last).
  HardCaseOutcome pressed(const std::string& name, const config::Scene& scene, const Adjust& adjust,
                  const std::function<void(fem::TissueModel&)>& after, const std::vector<double>& forces) {
    HardCaseOutcome o;
    o.name = name;
    auto model = build(scene, adjust);
    if (after) after(*model);
    const int patch = model->solver->add_contact_patch(site_.point, site_.radius);
    o.converged = true;
    for (double f : forces) {
      model->solver->set_patch_force(patch, press(f));
      const fem::SolveReport r = model->solver->solve(settings_);
      account(r, o);
      o.converged = o.converged && r.converged;
      if (!r.converged) break;
    }
    o.reached = model->solver->patch_displacement(patch) * site_.inward;
    inspect(*model->solver, o);
    must_converge(o);
    return o;
  }

  config::Scene scene_;
  bool builtin_;
  const HardCasesOptions& o_;
  fem::NewtonSettings settings_;
  Site site_;
};

// A cell's volume with the sign of its vertices' order (a tetrahedron; a hexahedron's first corner
// tetrahedron), so that a cell turned inside out changes sign.
double signed_volume(const dealii::Triangulation<3>::active_cell_iterator& cell) {
  const Point<3> a = cell->vertex(0);
  const Tensor<1, 3> b = cell->vertex(1) - a, c = cell->vertex(2) - a, d = cell->vertex(cell->n_vertices() == 4 ? 3 : 4) - a;
  return b * dealii::cross_product_3d(c, d) / 6;
}

config::Scene with_material(config::Scene scene, config::MaterialModel model, double nu, bool incompressibility) {
  const auto change = [&](config::Material& m) {
    if (m.model == config::MaterialModel::mooney_rivlin) return;  // keeps its own constants
    m.model = model, m.poisson_ratio = nu;
  };
  change(scene.material);
  for (config::RegionMaterial& r : scene.materials) change(r.material);
  auto& listed = scene.effects.listed;
  listed.erase(std::remove(listed.begin(), listed.end(), config::Effect::incompressibility), listed.end());
  if (incompressibility) listed.push_back(config::Effect::incompressibility);
  return scene;
}

std::vector<std::function<HardCaseOutcome()>> Battery::cases() {
  const double f = site_.force_n;
  std::vector<std::function<HardCaseOutcome()>> all;
  all.emplace_back([this]() {  // 40 % compression: the faces on the probe's side moved in by 40 % of the depth
    HardCaseOutcome o;
    o.name = "40 % compression";
    const Site s = site_;
    const bool from_top = s.inward[s.axis] < 0;  // the probe's side is the axis's upper end
    auto model = build(scene_, [s, from_top](dealii::Triangulation<3>& tria) {
      const double band = 0.02 * s.depth;
      for (const auto& cell : tria.active_cell_iterators())
        for (const unsigned int face : cell->face_indices())
          if (cell->face(face)->at_boundary()) {
            const double x = cell->face(face)->center()[s.axis];
            if (from_top ? x > s.hi - band : x < s.lo + band) cell->face(face)->set_boundary_id(kPressedFaces);
          }
    });
    Tensor<1, 3> moved;
    moved[s.axis] = (from_top ? -0.4 : 0.4) * s.depth;
    model->solver->prescribe_displacement(kPressedFaces, {true, true, true}, moved);
    fem::NewtonSettings one = settings_;
    one.load_steps = 1;  // on purpose: cutting has to find the way
    const fem::SolveReport r = model->solver->solve(one);
    account(r, o);
    o.converged = r.converged;
    inspect(*model->solver, o);
    must_converge(o);
    return o;
  });
  all.emplace_back([this, f]() {  // pushed until 30 % of the depth, the force growing by half each solve
    HardCaseOutcome o;
    o.name = "probe pushed 30 % of the depth";
    auto model = build(scene_, {});
    const int patch = model->solver->add_contact_patch(site_.point, site_.radius);
    o.converged = false;
    for (double force = f; force < 200 * f; force *= 1.5) {
      model->solver->set_patch_force(patch, press(force));
      const fem::SolveReport r = model->solver->solve(settings_);
      account(r, o);
      if (!r.converged) break;
      o.reached = model->solver->patch_displacement(patch) * site_.inward;
      if (o.reached >= 0.3 * site_.depth) {
        o.converged = true;
        break;
      }
    }
    inspect(*model->solver, o);
    must_converge(o);
    o.expected = "converged at 30 % of the depth";
    return o;
  });
  all.emplace_back([this, f]() {
    return pressed("nu = 0.4999, locking-free (mean dilatation)",
                   with_material(scene_, config::MaterialModel::neo_hookean_incompressible, 0.4999, true), {}, {}, {f});
  });
  all.emplace_back([this, f]() {
    return pressed("nu = 0.4999, displacement formulation", with_material(scene_, config::MaterialModel::neo_hookean, 0.4999, false),
                   {}, {}, {f});
  });
  all.emplace_back([this, f]() {  // the half of the tissue away from the probe 1e4 times stiffer
    const Site s = site_;
    const bool from_top = s.inward[s.axis] < 0;
    const Adjust layers = [s, from_top](dealii::Triangulation<3>& tria) {
      const double middle = 0.5 * (s.lo + s.hi);
      for (const auto& cell : tria.active_cell_iterators())
        if (from_top ? cell->center()[s.axis] < middle : cell->center()[s.axis] > middle) cell->set_material_id(kStiffRegion);
    };
    config::Material stiff = scene_.materials.empty() ? scene_.material : scene_.materials.front().material;
    if (stiff.model == config::MaterialModel::mooney_rivlin) stiff.c10_pa *= 1e4, stiff.c01_pa *= 1e4, stiff.bulk_modulus_pa *= 1e4;
    stiff.youngs_modulus_pa *= 1e4;
    auto material = std::make_shared<std::unique_ptr<fem::Material>>(fem::make_material(stiff));
    return pressed("1e4 stiffness ratio between regions", scene_, layers,
                   [material](fem::TissueModel& m) { m.solver->set_region_material(kStiffRegion, **material); }, {f});
  });
  all.emplace_back([this, f]() {
    // Every interior vertex moved at random by up to 0.4 of its shortest edge (the largest that
    // keeps a regular mesh's cells right side out); a smaller fraction where that turns one of an
    // unstructured mesh's cells inside out before any load (a mesh no solver should be given).
    auto used = std::make_shared<double>(0.4);
    const Adjust distort = [used](dealii::Triangulation<3>& tria) {
      const std::vector<Point<3>> original = tria.get_vertices();
      for (double fraction : {0.4, 0.3, 0.2, 0.1}) {
        for (const auto& cell : tria.active_cell_iterators())
          for (const unsigned int v : cell->vertex_indices()) cell->vertex(v) = original[cell->vertex_index(v)];
        std::vector<double> before;
        for (const auto& cell : tria.active_cell_iterators()) before.push_back(signed_volume(cell));
        dealii::GridTools::distort_random(fraction, tria, true, 11);
        std::size_t i = 0, flipped = 0;
        for (const auto& cell : tria.active_cell_iterators()) flipped += signed_volume(cell) * before[i++] <= 0;
        *used = fraction;
        if (flipped == 0) return;
      }
    };
    HardCaseOutcome o = pressed("sliver elements", scene_, distort, {}, {0.5 * f});
    char name[64];
    std::snprintf(name, sizeof name, "sliver elements (random distortion %.1f)", *used);
    o.name = name;
    return o;
  });
  all.emplace_back([this, f]() {
    return pressed("load reversal (press, pull, press)", scene_, {}, {}, {f, -0.5 * f, f});
  });
  all.emplace_back([this, f]() {  // two probes 3 radii apart, each pressing in and towards the other
    HardCaseOutcome o;
    o.name = "two probes converging";
    auto model = build(scene_, {});
    const Tensor<1, 3> t = site_.tangent;
    const Point<3> a = model->solver->boundary_point_nearest(site_.point - 1.5 * site_.radius * t, false);
    const Point<3> b = model->solver->boundary_point_nearest(site_.point + 1.5 * site_.radius * t, false);
    const int pa = model->solver->add_contact_patch(a, site_.radius), pb = model->solver->add_contact_patch(b, site_.radius);
    // The squeeze's stiffness: the pair's force against their approach, along t, by the condensed
    // compliance (1 / d'W d, d the unit vector of the two patches moving towards each other).
    const auto squeeze_stiffness = [&] {
      const dealii::FullMatrix<double> w = model->solver->compliance();
      std::vector<double> d(w.m(), 0.0);
      for (int c = 0; c < 3; ++c) d[std::size_t(3 * pa + c)] = t[c] / std::sqrt(2.0), d[std::size_t(3 * pb + c)] = -t[c] / std::sqrt(2.0);
      double wd = 0;
      for (unsigned int i = 0; i < w.m(); ++i)
        for (unsigned int j = 0; j < w.n(); ++j) wd += d[i] * w(i, j) * d[j];
      return 1 / wd;
    };
    const double at_rest = squeeze_stiffness();
    const auto load = [&](double factor) {
      model->solver->set_patch_force(pa, factor * 0.5 * f * (site_.inward + t));
      model->solver->set_patch_force(pb, factor * 0.5 * f * (site_.inward - t));
    };
    load(1);
    const fem::SolveReport r = model->solver->solve(settings_);
    account(r, o);
    o.converged = r.converged;
    if (r.converged) {
      o.reached = (model->solver->patch_displacement(pa) - model->solver->patch_displacement(pb)) * t;
      inspect(*model->solver, o);
      must_converge(o);
      o.expected = "converged, or stopped where the tissue loses stability";
      return o;
    }
    // Squeezed from both sides, the wall over the liquid can fold, or the liquid's thin layer
    // between wall and fetus give way: past the load where the tissue loses its stability no
    // stable state near the last one carries more, and force control cannot go on. That is the
    // tissue's answer, not the solver's failure, when the squeeze's stiffness at the last load
    // reached has fallen under a quarter of its value at rest (at a limit point it tends to zero;
    // past a bifurcation it is negative), by the condensed compliance and by finite differences.
    o.expected = "converged, or stopped where the tissue loses stability";
    inspect(*model->solver, o);
    // Rolled back: the state before the solve, at rest.
    const bool rolled_back = o.finite && o.min_j > 0 && model->solver->patch_displacement(pa).norm() == 0 &&
                             model->solver->patch_displacement(pb).norm() == 0;
    double reached_factor = 0;
    for (const fem::StepReport& step : r.steps)
      if (step.converged) reached_factor = std::max(reached_factor, step.load_factor);
    if (reached_factor <= 0 || !rolled_back) return o;
    load(reached_factor);
    const fem::SolveReport again = model->solver->solve(settings_);
    account(again, o);
    if (!again.converged) return o;
    const double there = squeeze_stiffness();
    o.reached = (model->solver->patch_displacement(pa) - model->solver->patch_displacement(pb)) * t;
    inspect(*model->solver, o);
    // The same stiffness by a finite difference (the state under a little less squeeze: on the
    // side where a nearby state exists), so that the verdict does not rest on the compliance's own
    // solves alone. d'u = approach / sqrt(2) under d'f = -eps.
    const double eps = 1e-3 * f;
    model->solver->set_patch_force(pa, reached_factor * 0.5 * f * (site_.inward + t) - eps / std::sqrt(2.0) * t);
    model->solver->set_patch_force(pb, reached_factor * 0.5 * f * (site_.inward - t) + eps / std::sqrt(2.0) * t);
    const fem::SolveReport eased = model->solver->solve(settings_);
    account(eased, o);
    if (!eased.converged) return o;
    const double eased_approach = (model->solver->patch_displacement(pa) - model->solver->patch_displacement(pb)) * t;
    const double by_differences = eps * std::sqrt(2.0) / (o.reached - eased_approach);
    const bool lost = there < 0.25 * at_rest && by_differences < 0.25 * at_rest;
    char text[320];
    std::snprintf(text, sizeof text,
                  "; %s: at %.1f %% of the load the squeeze's stiffness is %.3g N/m (%.3g by finite differences; %.3g at rest%s)",
                  lost ? "stability lost" : "no loss of stability shown", 100 * reached_factor, there, by_differences, at_rest,
                  lost ? "" : "; a loss asks under a quarter of it");
    o.failure = r.failure + text;
    o.sound = lost && o.min_j > 0 && o.finite;
    return o;
  });
  all.emplace_back([this]() {  // beyond what the tissue can take: it must fail cleanly and roll back
    HardCaseOutcome o;
    o.name = "impossible load (500 N)";
    auto model = build(scene_, {});
    const int patch = model->solver->add_contact_patch(site_.point, site_.radius);
    model->solver->set_patch_force(patch, press(0.1));
    fem::SolveReport r = model->solver->solve(settings_);
    account(r, o);
    const Tensor<1, 3> before = model->solver->patch_displacement(patch);
    model->solver->set_patch_force(patch, press(500));
    fem::NewtonSettings few = settings_;
    few.max_cuts = std::min(few.max_cuts, 4);
    r = model->solver->solve(few);
    account(r, o);
    o.converged = r.converged;
    inspect(*model->solver, o);
    const bool rolled_back = model->solver->patch_displacement(patch) == before;
    o.expected = "failed cleanly, rolled back";
    o.sound = !r.converged && !r.failure.empty() && rolled_back && o.min_j > 0 && o.finite;
    if (!r.converged && !rolled_back) o.failure += " (not rolled back)";
    return o;
  });
  all.emplace_back([this, f]() {  // frames through the environment: a probe that jumps across the surface
    return through_environment("probe teleported across the surface", f, true);
  });
  all.emplace_back([this, f]() { return through_environment("a frame with an over-limit force request (1000 N)", f, false); });
  return all;
}

// Two frames through the tissue's environment, as a session sends them: a press at the patch, then
// either the same press a far way across the surface (the patch follows the probe in one frame) or
// a force far over any device's limit. The second frame must converge, or fail and hand back the
// last good answer.
HardCaseOutcome Battery::through_environment(const std::string& name, double force, bool teleport) {
  HardCaseOutcome o;
  o.name = name;
  auto model = build(scene_, {});
  model->solver->add_contact_patch(site_.point, site_.radius);
  fem::NewtonSettings newton = model->newton;
  newton.max_cuts = settings_.max_cuts, newton.line_search = settings_.line_search;
  fem::FemEnvironment tissue(std::move(model->solver), newton);
  haptics::EnvironmentUpdate out;
  tissue.initial(out);
  std::vector<haptics::ContactSample> samples(1);
  samples[0].position = {site_.point[0], site_.point[1], site_.point[2]};
  samples[0].force = {press(force)[0], press(force)[1], press(force)[2]};
  samples[0].normal_force = force, samples[0].in_contact = true;
  tissue.solve(samples, 0, out);
  account(tissue.last_report(), o);
  const haptics::EnvironmentUpdate first = out;
  if (teleport) {
    const Point<3> far = tissue.solver().boundary_point_nearest(site_.point + 4 * site_.radius * site_.tangent, false);
    samples[0].position = {far[0], far[1], far[2]};
  } else {
    samples[0].force *= 1000 / force, samples[0].normal_force = 1000;
  }
  tissue.solve(samples, 1, out);
  account(tissue.last_report(), o);
  o.converged = out.status.converged;
  inspect(tissue.solver(), o);
  bool finite = out.compliance.allFinite();
  for (const haptics::ContactFrame& frame : out.frames) finite = finite && frame.point.allFinite() && frame.normal.allFinite();
  o.finite = o.finite && finite;
  if (teleport) {
    must_converge(o);
    o.sound = o.sound && tissue.patch_moves() > 0;
    if (tissue.patch_moves() == 0) o.failure = "the patch did not follow the probe";
  } else {
    o.expected = "converged, or failed with the last good answer kept";
    const bool kept = !out.status.converged && out.compliance.isApprox(first.compliance) && !out.status.message.empty();
    o.sound = o.finite && o.min_j > 0 && (out.status.converged || kept);
    if (!out.status.converged) o.failure = out.status.message;
  }
  return o;
}

}  // namespace

int run_study_hard_cases(const HardCasesOptions& o) {
  const bool builtin = o.scene.empty();
  config::Scene scene;
  if (builtin) {
    scene = builtin_block();
  } else {
    std::optional<config::Scene> loaded = load_scene_or_report(o.scene);
    if (!loaded) return kExitBadInput;
    scene = std::move(*loaded);
    if (scene.probes.empty()) {
      std::cerr << "error: " << o.scene << ": the scene has no probe to say where the cases press\n";
      return kExitBadInput;
    }
  }
  const fs::path out(o.out);
  if (!builtin) prepare_study_folder(out, o.scene, scene);
  fs::create_directories(out);
  scene.mesh = mesh_scene_volume(scene);
  Battery battery(scene, builtin, o);
  const auto cases = battery.cases();
  Progress progress("study hard-cases", static_cast<long>(cases.size()), std::cerr, Progress::stderr_is_terminal());
  std::vector<HardCaseOutcome> outcomes;
  for (const auto& run_case : cases) {
    const auto start = std::chrono::steady_clock::now();
    HardCaseOutcome c;
    try {
      c = run_case();
    } catch (const std::exception& e) {  // a case that throws is not sound, and the others still run
      c.name = c.name.empty() ? "case " + std::to_string(outcomes.size() + 1) : c.name;
      c.failure = std::string("threw: ") + e.what();
      c.sound = false;
    }
    c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    c.result = c.converged ? "converged" : (c.failure.empty() ? "not converged" : "cut: " + c.failure);
    log::info() << c.name << ": " << (c.sound ? "sound" : "NOT SOUND") << ", " << c.result;
    outcomes.push_back(std::move(c));
    progress.update(static_cast<long>(outcomes.size()));
  }
  progress.finish();
  const Site& site = battery.site();
  std::ostringstream setting;
  setting << (builtin ? std::string("A 10 x 8 x 5 cm block of P2 tetrahedra, neo-Hookean (E = 5 kPa, nu = 0.45), on a table.")
                      : "Scene `" + o.scene + "`: its mesh, materials and supports.")
          << " The probe presses at (" << site.point << ") m, inward along (" << site.inward << "), radius " << site.radius
          << " m; the tissue's depth along axis " << "xyz"[site.axis] << " is " << site.depth << " m; a firm press is "
          << site.force_n << " N. Newton: " << (o.no_line_search ? "**no line search**" : "line search") << ", at most "
          << (o.max_cuts >= 0 ? o.max_cuts : 8) << " load-step cuts.";
  const bool all_sound = write_hard_cases_outputs(out, builtin ? std::string("block") : scene.name,
                                                  builtin ? "the built-in block" : scene.name, setting.str(), outcomes, o.json);
  return all_sound ? kExitOk : kExitFailure;
}

}  // namespace fetouch::app
