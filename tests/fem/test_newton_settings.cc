// Every Newton key of a scene's `solver` has the effect docs/scenes.md gives it, through the scene
// (config -> tissue model -> solver), on a soft block pressed hard in one step; the accuracy policy
// keeps its promise against a tightly converged answer; and a term the scene does not ask for is
// never built, so no solve ever calls it.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "config/scene_loader.h"
#include "fem/tissue_model.h"

namespace fetouch::fem {
namespace {

// A 10 x 8 x 5 cm neo-Hookean block (E = 5 kPa) on a table, pressed by 2 kPa over a band of its top:
// about 20 % compression under the band, a few Newton iterations from rest.
std::string block(const std::string& solver, const std::string& effects = "  - contact\n") {
  return "name: s\nunits: SI\nmesh:\n  generate: {shape: box, size_m: [0.1, 0.08, 0.05], refinements: 1}\n"
         "  element: p1\nmaterial: {model: neo_hookean, youngs_modulus_pa: 5000, poisson_ratio: 0.45}\n"
         "effects:\n" + effects +
         "boundary:\n  - {name: table, type: fixed, select: {physical_group: zmin}}\n"
         "  - {name: press, type: traction, traction_pa: [0, 0, -2000], "
         "select: {box: {min: [0.03, -1, 0.0499], max: [0.07, 1, 1]}}}\n"
         "solver: " + solver + "\n";
}

std::unique_ptr<TissueModel> model(const std::string& text) {
  return build_tissue_model(config::parse_scene(text, "test", ".").scene);
}

SolveReport solve(const std::string& solver) {
  auto m = model(block(solver));
  return m->solver->solve(m->newton);
}

TEST(NewtonSettings, RelativeToleranceEndsNewtonAtItsReduction) {
  const SolveReport loose = solve("{newton: {relative_tolerance: 1.0e-3}}");
  const SolveReport tight = solve("{newton: {relative_tolerance: 1.0e-11}}");
  ASSERT_TRUE(loose.converged && tight.converged);
  for (const auto* r : {&loose, &tight}) ASSERT_EQ(r->steps.size(), 1u);
  const auto& l = loose.steps[0].residuals;
  const auto& t = tight.steps[0].residuals;
  EXPECT_LE(l.back(), 1e-3 * l.front());
  EXPECT_GT(l[l.size() - 2], 1e-3 * l.front());  // it stopped at the first iterate below the reduction
  EXPECT_LE(t.back(), 1e-11 * t.front());
  EXPECT_LT(loose.total_iterations, tight.total_iterations);
}

TEST(NewtonSettings, AbsoluteToleranceEndsNewtonAtItsNorm) {
  // The first residual is the press, 2 kPa x 0.04 x 0.08 m = 6.4 N spread over the band's nodes: a
  // norm of the order of 1 N. 100 N accepts the unloaded state; 1e-12 N does not.
  const SolveReport huge = solve("{newton: {absolute_tolerance: 100}}");
  ASSERT_TRUE(huge.converged);
  EXPECT_EQ(huge.total_iterations, 0);
  EXPECT_LT(huge.steps[0].residuals[0], 100);
  EXPECT_GT(solve("{newton: {absolute_tolerance: 1.0e-12}}").total_iterations, 0);
}

TEST(NewtonSettings, MaxIterationsBoundsEachStepAndCutsFollow) {
  const SolveReport free = solve("{newton: {max_iterations: 25}}");
  ASSERT_TRUE(free.converged);
  ASSERT_GT(free.total_iterations, 2);  // the press needs more than two iterations from rest
  const SolveReport two = solve("{newton: {max_iterations: 2, max_load_step_cuts: 0}}");
  EXPECT_FALSE(two.converged);
  ASSERT_EQ(two.steps.size(), 1u);
  EXPECT_EQ(two.steps[0].residuals.size(), 3u);  // the start and two iterations
  EXPECT_NE(two.failure.find("no convergence in 2 Newton iterations"), std::string::npos) << two.failure;
}

TEST(NewtonSettings, MaxLoadStepCutsBoundsTheHalvings) {
  // Two iterations are too few for the whole load, so steps are halved: at most `cuts` times.
  for (const int cuts : {0, 1, 3}) {
    const SolveReport r = solve("{newton: {max_iterations: 2, max_load_step_cuts: " + std::to_string(cuts) + "}}");
    if (r.converged) {
      EXPECT_LE(r.cuts, cuts);
      continue;
    }
    EXPECT_EQ(r.cuts, cuts + 1) << "cuts " << cuts;
    EXPECT_NE(r.failure.find("after " + std::to_string(cuts) + " cuts"), std::string::npos) << r.failure;
  }
  // Enough cuts let the small steps through.
  const SolveReport many = solve("{newton: {max_iterations: 2, max_load_step_cuts: 12}}");
  EXPECT_TRUE(many.converged) << many.failure;
  EXPECT_GT(many.cuts, 0);
}

// Once the cuts are spent on a step that ran out of iterations, that step is tried once more with
// four times the iterations (a snap past a loss of stability cannot be cut away: docs/solver.md).
// Three iterations are too few for the press in one step or in two; twelve carry its first half.
TEST(NewtonSettings, AStepWhoseCutsAreSpentIsTriedOnceWithFourTimesTheIterations) {
  const auto attempts = [](const SolveReport& r) {
    std::vector<std::pair<double, int>> tried;  // load factor, iterations taken
    for (const StepReport& step : r.steps) tried.emplace_back(step.load_factor, int(step.residuals.size()) - 1);
    return tried;
  };
  const auto reference = model(block("{newton: {max_iterations: 25}}"));
  ASSERT_TRUE(reference->solver->solve(reference->newton).converged);
  const double answer = reference->solver->max_displacement();

  const auto m = model(block("{newton: {max_iterations: 3, max_load_step_cuts: 1}}"));
  const SolveReport r = m->solver->solve(m->newton);
  const auto tried = attempts(r);
  ASSERT_GE(tried.size(), 3u) << r.failure;
  EXPECT_EQ(tried[0], std::make_pair(1.0, 3));  // the whole load: failed
  EXPECT_EQ(tried[1], std::make_pair(0.5, 3));  // half of it: failed, the one cut spent
  EXPECT_EQ(tried[2].first, 0.5);               // half again, with up to 12 iterations
  EXPECT_GT(tried[2].second, 3);
  EXPECT_LE(tried[2].second, 12);
  EXPECT_TRUE(r.steps[2].converged);
  ASSERT_TRUE(r.converged) << r.failure;  // the second half then converges from the first's path
  EXPECT_EQ(r.cuts, 1);
  EXPECT_NEAR(m->solver->max_displacement(), answer, 1e-7 * answer);

  // Only once: with two iterations the second half fails as well, and that ends the solve.
  const SolveReport two = solve("{newton: {max_iterations: 2, max_load_step_cuts: 1}}");
  const auto tried_two = attempts(two);
  ASSERT_GE(tried_two.size(), 4u) << two.failure;
  EXPECT_EQ(tried_two[2].first, 0.5);
  EXPECT_GT(tried_two[2].second, 2);
  EXPECT_LE(tried_two[2].second, 8);
  for (std::size_t k = 3; k < tried_two.size(); ++k) EXPECT_LE(tried_two[k].second, 2) << "attempt " << k;
  EXPECT_FALSE(two.converged);
  EXPECT_EQ(two.cuts, 2);
  EXPECT_NE(two.failure.find("after 1 cuts"), std::string::npos) << two.failure;

  // With the cuts off there is no second try.
  const SolveReport off = solve("{newton: {max_iterations: 3, max_load_step_cuts: 0}}");
  EXPECT_EQ(off.steps.size(), 1u);
  EXPECT_FALSE(off.converged);
}

TEST(NewtonSettings, LineSearchTamesTheFullStepsThatOvershoot) {
  // A harder press (6 kPa) in one step: the full Newton steps from rest overshoot (some raises the
  // residual, or inverts an element). The line search, which scales a step that overshoots the
  // energy's minimum along it, converges in that one step; without it the history differs.
  const auto hard = [&](bool search) {
    std::string text = block(search ? "{newton: {line_search: true, max_load_step_cuts: 0}}"
                                    : "{newton: {line_search: false, max_load_step_cuts: 0}}");
    text.replace(text.find("-2000"), 5, "-6000");
    auto m = model(text);
    EXPECT_EQ(m->newton.line_search, search);
    return m->solver->solve(m->newton);
  };
  const SolveReport a = hard(true), b = hard(false);
  ASSERT_FALSE(a.steps.empty());
  ASSERT_FALSE(b.steps.empty());
  EXPECT_TRUE(a.converged) << a.failure;
  EXPECT_EQ(a.cuts, 0);
  const auto& rb = b.steps[0].residuals;
  bool rose = !b.converged;
  for (std::size_t i = 1; i < rb.size(); ++i) rose = rose || rb[i] > rb[i - 1];
  EXPECT_TRUE(rose);
  EXPECT_NE(a.steps[0].residuals, rb);
}

TEST(NewtonSettings, LaterLoadStepsStartFromTheExtrapolatedPath) {
  // A gentle press (20 Pa, strains of 1e-3) answers almost linearly in the load: the secant through
  // the last two converged states predicts the next within O(strain) of the increment's answer, so
  // the second step starts with a residual far below the first step's (the load increment's); each
  // step still ends at 1e-8 of the increment's residual.
  std::string text = block("{newton: {relative_tolerance: 1.0e-8}}");
  text.replace(text.find("-2000"), 5, "-20  ");
  auto m = model(text);
  NewtonSettings four = m->newton;
  four.load_steps = 4;
  const SolveReport r = m->solver->solve(four);
  ASSERT_TRUE(r.converged) << r.failure;
  ASSERT_EQ(r.steps.size(), 4u);
  const double increment = r.steps[0].residuals.front();
  for (std::size_t k = 1; k < 4; ++k) {
    EXPECT_LT(r.steps[k].residuals.front(), 1e-2 * increment) << "step " << k;
    EXPECT_LE(r.steps[k].residuals.back(), 1e-8 * increment * 1.000001) << "step " << k;
  }
  EXPECT_LT(r.steps[3].iterations, r.steps[0].iterations);
}

// A frame: the press held, a probe's force changed by 5 %, solved with the accuracy policy and
// without it (to 1e-12): the contact's displacement agrees within the policy's position tolerance,
// in fewer iterations.
TEST(NewtonSettings, AccuracyPolicyKeepsTheContactWithinItsTolerance) {
  const auto frame = [](const std::string& solver, SolveReport& report) {
    auto m = model(block(solver));
    const int patch = m->solver->add_contact_patch(dealii::Point<3>(0.05, 0.04, 0.05), 0.01);
    dealii::Tensor<1, 3> force;
    force[2] = -0.5;
    m->solver->set_patch_force(patch, force);
    EXPECT_TRUE(m->solver->solve(m->newton).converged);
    m->solver->compliance();
    force[2] = -0.525;
    m->solver->set_patch_force(patch, force);
    report = m->solver->solve(m->newton);
    return m->solver->patch_displacement(patch);
  };
  SolveReport policy, tight;
  const auto u_policy = frame("{accuracy: {position_m: 1.0e-5, force_n: 1.0e-3}}", policy);
  const auto u_tight = frame("{accuracy: none, newton: {relative_tolerance: 1.0e-12}}", tight);
  ASSERT_TRUE(policy.converged && tight.converged);
  EXPECT_LT((u_policy - u_tight).norm(), 1e-5);
  EXPECT_LT(policy.total_iterations, tight.total_iterations);
  EXPECT_TRUE(policy.steps.back().accurate);
  // A tighter policy is honoured too.
  SolveReport finer;
  const auto u_finer = frame("{accuracy: {position_m: 1.0e-8, force_n: 1.0e-6}}", finer);
  EXPECT_LT((u_finer - u_tight).norm(), 1e-8);
}

// The frame bound: one Newton iteration (or the first after it that is down a hundredfold) for a
// large force change, the remainder carried; the next frames (same force) pick it up and end where
// a single tight solve does.
TEST(NewtonSettings, FrameIterationsCarryTheRemainderToTheNextFrame) {
  auto m = model(block("{accuracy: {position_m: 1.0e-9, force_n: 1.0e-7}, frame_newton_iterations: 1}"));
  const int patch = m->solver->add_contact_patch(dealii::Point<3>(0.05, 0.04, 0.05), 0.01);
  dealii::Tensor<1, 3> force;
  force[2] = -0.2;
  m->solver->set_patch_force(patch, force);
  ASSERT_TRUE(m->solver->solve(m->newton).converged);
  m->solver->compliance();
  force[2] = -1.0;  // five times the force: more than one Newton iteration's worth
  m->solver->set_patch_force(patch, force);
  const SolveReport first = m->solver->solve(m->newton);
  EXPECT_TRUE(first.converged);
  EXPECT_TRUE(first.carried);
  // It stopped at the first iterate past the bound whose residual is down a hundredfold.
  const auto& r = first.steps.back().residuals;
  ASSERT_GE(r.size(), 2u);
  EXPECT_LE(r.back(), 1e-2 * r.front());
  if (r.size() > 2) {
    EXPECT_GT(r[r.size() - 2], 1e-2 * r.front());
  }
  EXPECT_GT(r.back(), 1e-9 * r.front());  // well short of converged: there is a remainder to carry
  m->solver->compliance();
  SolveReport next;
  for (int frame = 0; frame < 5 && (frame == 0 || next.carried); ++frame) {
    next = m->solver->solve(m->newton);
    m->solver->compliance();
  }
  EXPECT_FALSE(next.carried);
  auto reference = model(block("{accuracy: none, newton: {relative_tolerance: 1.0e-12}}"));
  const int p = reference->solver->add_contact_patch(dealii::Point<3>(0.05, 0.04, 0.05), 0.01);
  reference->solver->set_patch_force(p, force);
  ASSERT_TRUE(reference->solver->solve(reference->newton).converged);
  EXPECT_LT((m->solver->patch_displacement(patch) - reference->solver->patch_displacement(p)).norm(), 1e-8);
}

// Effects are terms built only when the scene lists them: none of another effect's is ever made,
// so no assembly calls it (the solve's per-term profile names exactly the terms built).
TEST(SolverTerms, AnEffectTheSceneDoesNotListIsNeverBuilt) {
  const auto terms = [](const std::string& effects, bool patch) {
    std::string text = block("{}", effects);
    auto m = model(text);
    if (patch) m->solver->add_contact_patch(dealii::Point<3>(0.05, 0.04, 0.05), 0.01);
    if (auto d = scene_dynamics(config::parse_scene(text, "test", ".").scene)) m->solver->enable_dynamics(*d);
    const SolveReport r = m->solver->solve(m->newton);
    EXPECT_TRUE(r.converged);
    std::vector<std::string> profiled;
    for (const fem::SolveReport::TermTime& t : r.terms) profiled.push_back(t.name);
    EXPECT_EQ(profiled, m->solver->terms());
    return m->solver->terms();
  };
  using Names = std::vector<std::string>;
  // The press is a traction: the loads term. Nothing else.
  EXPECT_EQ(terms("  - contact\n", false), (Names{"elasticity", "loads"}));
  EXPECT_EQ(terms("  - contact\n", true), (Names{"elasticity", "loads", "contact"}));
  EXPECT_EQ(terms("  - gravity\n", false), (Names{"elasticity", "loads"}));
  EXPECT_EQ(terms("  - inertia\n", false), (Names{"elasticity", "inertia", "loads"}));
  EXPECT_EQ(terms("  - inertia\n  - damping: {stiffness_coefficient_s: 0.01}\n", false),
            (Names{"elasticity", "inertia", "damping", "loads"}));
  // Without the traction region either: elasticity alone.
  std::string bare = block("{}");
  bare.erase(bare.find("  - {name: press"), bare.find("solver:") - bare.find("  - {name: press"));
  EXPECT_EQ(model(bare)->solver->terms(), (Names{"elasticity"}));
}

}  // namespace
}  // namespace fetouch::fem
