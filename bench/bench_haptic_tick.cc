// One haptic tick (architecture budget: under 5 us for 4 contacts, compute only): device points in,
// forces out, through hold, contact geometry, local model, the passivity layer (argument
// `passivity`: 0 off, 1 observe, 2 on), the on-line identification (argument `identification`: 0
// off, 1 on; the devices move, so it learns at every tick) and the safety layer. Driven by the
// lockstep session with fixed gains, so every 50th tick also carries the linear environment's
// solve (amortised, a few ns); gain selection is the producer's work and is measured by
// BM_SelectGains4Contacts.
#include <benchmark/benchmark.h>

#include <cmath>

#include "haptics/haptic_loop.h"
#include "haptics/linear_surface_environment.h"

namespace {

using namespace fetouch::haptics;

void BM_HapticTick(benchmark::State& state) {
  const auto kind = static_cast<LocalModelKind>(state.range(0));
  const auto hold = static_cast<HoldKind>(state.range(1));
  const int contacts = static_cast<int>(state.range(2));
  HapticLoopSettings settings;
  settings.passivity.mode = static_cast<PassivityMode>(state.range(3));
  settings.identification.enabled = state.range(4) != 0;
  settings.local_model = kind;
  settings.hold = hold;
  settings.schedule_gains = false;
  settings.gains = {200, 100.0 / 50};
  std::vector<ContactFrame> rest(contacts);
  for (int c = 0; c < contacts; ++c) {
    rest[c].point = {0.015 * c, 0, 0};
    rest[c].curvature = Eigen::Matrix2d::Identity() * 20;
  }
  Eigen::MatrixXd k0 = Eigen::MatrixXd::Identity(3 * contacts, 3 * contacts) * 600;
  for (int c = 0; c + 1 < contacts; ++c) k0(3 * c + 2, 3 * c + 5) = k0(3 * c + 5, 3 * c + 2) = -150;
  LinearSurfaceEnvironment environment(rest, k0, 0.05 * k0);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> devices(contacts);
  long k = 0;
  for (auto _ : state) {
    for (int c = 0; c < contacts; ++c)
      devices[c] = rest[c].point + Eigen::Vector3d(0.001, 0, -0.002 - 0.001 * std::sin(1e-3 * k));
    benchmark::DoNotOptimize(session.tick(devices).data());
    ++k;
  }
}
BENCHMARK(BM_HapticTick)
    ->ArgNames({"model", "hold", "contacts", "passivity", "identification"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}, {1, 4}, {0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kNanosecond);

}  // namespace
