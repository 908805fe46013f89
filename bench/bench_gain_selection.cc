// Robust gain selection for four coupled contacts (architecture budget: under 1 ms, since it runs
// once per solver frame, on the solver's side of the hand-over). The stiffness is a 4 x 4 matrix
// with couplings, as two fingers on a soft organ produce.
#include <benchmark/benchmark.h>

#include "haptics/gain_selection.h"

namespace {

using namespace fetouch::haptics;

GainProblem four_contacts(LocalModelKind kind, HoldKind hold) {
  GainProblem problem;
  problem.local_model = kind;
  problem.hold = hold;
  problem.ratio = 50;
  problem.stiffness.resize(4, 4);
  problem.stiffness << 800, -300, -100, -50,   //
      -300, 900, -200, -80,                    //
      -100, -200, 700, -250,                   //
      -50, -80, -250, 1000;                    // N/m
  problem.damping = Eigen::MatrixXd::Identity(4, 4) * 20;
  return problem;
}

void BM_SelectGains4Contacts(benchmark::State& state) {
  const auto kind = static_cast<LocalModelKind>(state.range(0));
  const auto hold = static_cast<HoldKind>(state.range(1));
  const GainProblem problem = four_contacts(kind, hold);
  int evaluations = 0;
  for (auto _ : state) {
    const GainSelection g = select_gains(problem);
    evaluations = g.evaluations;
    benchmark::DoNotOptimize(g);
  }
  state.counters["scalar_loops"] = evaluations;
}
BENCHMARK(BM_SelectGains4Contacts)
    ->ArgNames({"model", "hold"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

namespace {

// Per frame at run time: the stiffness drifts a few percent and the previous gains warm-start the
// search (what the gain scheduler does).
void BM_ReselectGains4ContactsWarm(benchmark::State& state) {
  const auto kind = static_cast<LocalModelKind>(state.range(0));
  const auto hold = static_cast<HoldKind>(state.range(1));
  GainProblem problem = four_contacts(kind, hold);
  const GainSelection previous = select_gains(problem);
  problem.stiffness *= 1.03;
  int evaluations = 0;
  for (auto _ : state) {
    const GainSelection g = select_gains(problem, {}, &previous.gains);
    evaluations = g.evaluations;
    benchmark::DoNotOptimize(g);
  }
  state.counters["scalar_loops"] = evaluations;
}
BENCHMARK(BM_ReselectGains4ContactsWarm)
    ->ArgNames({"model", "hold"})
    ->ArgsProduct({{1, 3}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
