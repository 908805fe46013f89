// The frame-rate energy audit (haptic_loop.h, FrameEnergy) against independent answers: the hand's
// energy against the passivity port's observer (a second implementation of the same sum), the
// tissue's work against the elastic energy of a linear tissue at the end (closed form), the books
// closing frame by frame, and generating frames where a hand rings the loop and none where a
// passive rendering (the P local model's spring) meets a hand that does not ring it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "haptics/devices.h"
#include "haptics/haptic_loop.h"
#include "haptics/linear_surface_environment.h"

namespace fetouch::haptics {
namespace {

constexpr double kPeriod = 1e-3;

struct Audited {
  double hand = 0, tissue = 0, held_end = 0;
  long generating_frames = 0, frames = 0;
  double observer_energy = 0, tissue_elastic = 0;
};

std::vector<ContactFrame> flat_rest() {
  std::vector<ContactFrame> rest(1);
  rest[0].normal = Eigen::Vector3d::UnitZ();
  return rest;
}

// Sums the audit over every frame that ended (frame_energy() after each tick that decimated).
void take(const HapticLoop& loop, Audited& a) {
  if (!loop.decimated() || loop.ticks() <= 1) return;
  const FrameEnergy& e = loop.frame_energy()[0];
  a.hand += e.hand_j, a.tissue += e.tissue_j, a.held_end = e.held_j;
  ++a.frames;
  EXPECT_NEAR(a.held_end, a.hand - a.tissue, 1e-12);  // one contact from the start: held is the running balance
}

// A device driven along a path (no hand): pressed 3 mm into a linear tissue in 0.3 s and held.
// Every frame's books close: the hand's energy summed over the frames is the port observer's E at
// the last frame's end, and the tissue's work is the tissue's elastic energy K0 u^2 / 2 there.
TEST(EnergyAudit, HandAndTissueTermsMatchTheObserverAndTheElasticEnergy) {
  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi_smith}) {
    SCOPED_TRACE(to_string(kind));
    const double stiffness = 500;
    LinearSurfaceEnvironment environment = LinearSurfaceEnvironment::isotropic(flat_rest(), stiffness);
    HapticLoopSettings settings;
    settings.local_model = kind;
    settings.passivity.mode = PassivityMode::observe;
    settings.safety.max_force_n = 50;
    HapticLoop loop(settings, initial_update(environment));
    LockstepSession session(loop, environment);
    Audited a;
    double u = 0;  // the surface's displacement in the last answer the audited frames took up
    for (long k = 0; k <= 1000; ++k) {  // 1000 is a frame's first tick: the books of frame 19 close there
      const double t = k * kPeriod, depth = t < 0.3 ? 0.01 * t : 3e-3;
      session.tick({Eigen::Vector3d(0, 0, -depth)}, {Eigen::Vector3d(0, 0, t < 0.3 ? -0.01 : 0.0)});
      take(loop, a);
      if (k == 999) u = loop.newest().update.frames[0].point.z();  // taken up at tick 950
    }
    // Both pair f(k-1) with x(k) - x(k-1) at tick k, the observer in the passivity port.
    a.observer_energy = loop.passivity(0).energy_j();
    EXPECT_NEAR(a.hand, a.observer_energy, 1e-12 + 1e-9 * std::abs(a.observer_energy));
    const double elastic = 0.5 * stiffness * u * u;
    EXPECT_GT(elastic, 1e-5);
    EXPECT_NEAR(a.tissue, elastic, 1e-9 * elastic);
    EXPECT_EQ(a.frames, 20);
  }
}

// A hand on the tissue through the loop, the layer only observing: the light, stiff, barely damped
// grip of the issue on a stiff tissue rings and the audit counts generating frames; the default
// hand on a soft tissue does not ring and no frame generates.
long generating_frames(const HandParameters& hand_parameters, double stiffness, LocalModelKind kind) {
  LinearSurfaceEnvironment environment = LinearSurfaceEnvironment::isotropic(flat_rest(), stiffness);
  HapticLoopSettings settings;
  settings.local_model = kind;
  settings.passivity.mode = PassivityMode::observe;
  settings.safety.max_force_n = 8.5;
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  Trajectory path;
  path.times_s = {0, 0.3, 2.0};
  path.positions_m = {Eigen::Vector3d(0, 0, 2e-3), Eigen::Vector3d(0, 0, -3e-3), Eigen::Vector3d(0, 0, -3e-3)};
  VirtualOperator hand(path, hand_parameters, kPeriod);
  while (!hand.finished()) {
    const DeviceState state = hand.read();
    hand.write(session.tick({state.position_m}, {state.velocity_m_per_s})[0].force);
  }
  return loop.generating_frames(0);
}

TEST(EnergyAudit, CountsFramesThatGenerateWhereAHandRingsTheLoopAndNoneWhereNot) {
  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::pi_smith}) {
    SCOPED_TRACE(to_string(kind));
    EXPECT_GT(generating_frames(HandParameters{0.02, 2000, 0.5}, 20000, kind), 20);  // of 40 frames
  }
  EXPECT_EQ(generating_frames(HandParameters{0.6, 300, 8}, 300, LocalModelKind::p), 0);
}

}  // namespace
}  // namespace fetouch::haptics
