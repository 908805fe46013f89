// The safety filter runs on every device write, every tick: it must cost well under a microsecond.
#include <benchmark/benchmark.h>

#include "haptics/force_safety.h"

namespace {

void BM_ForceSafetyFilter(benchmark::State& state) {
  fetouch::haptics::ForceSafety safety({});
  Eigen::Vector3d request(0.5, -0.2, 1.0);
  double age = 0.0;
  for (auto _ : state) {
    request.x() = -request.x();  // alternate so the rate limit and clamp both do work
    benchmark::DoNotOptimize(safety.filter(request, age));
    age = age > 0.3 ? 0.0 : age + 1e-3;
  }
}
BENCHMARK(BM_ForceSafetyFilter);

}  // namespace
