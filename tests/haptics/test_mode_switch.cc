// Switching local model and hold while the loop runs (the trainer's control): the producer analyses
// the asked mode on the frame's stiffness and the tick takes it up with its gains, or the request
// is refused with the reason and nothing changes. The verdicts are checked against the stability
// analysis run here on the tissue's known stiffness and damping (400 N/m, 20 N s/m), and the
// rendered force against the new model's law.
#include <gtest/gtest.h>

#include <string>

#include "haptics/gain_selection.h"
#include "haptics/haptic_loop.h"
#include "haptics/linear_surface_environment.h"

namespace fetouch::haptics {
namespace {

constexpr double kStiffness = 400, kDamping = 20;

GainProblem problem_for(LocalModelKind model, HoldKind hold) {
  GainProblem problem;
  problem.local_model = model;
  problem.hold = hold;
  problem.ratio = 50;
  problem.stiffness = Eigen::MatrixXd::Constant(1, 1, kStiffness);
  problem.damping = Eigen::MatrixXd::Constant(1, 1, kDamping);
  return problem;
}

// A press held 3 mm deep; `ask` at frame `ask_frame`; returns the frame at which the tick took up
// the asked mode (-1: never) after running `frames` frames.
struct SwitchRun {
  long switched_at = -1;
  double worst_p_law = 0;  // |F - Kh e| over the ticks in contact after the switch (P only)
};
SwitchRun run(HapticLoop& loop, LinearSurfaceEnvironment& environment, ModeChannel& channel, LocalModelKind model, HoldKind hold,
        long ask_frame, long frames) {
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> device(1, Eigen::Vector3d(0.001, 0, -0.003));
  SwitchRun r;
  for (long k = 0; k < frames * 50; ++k) {
    if (k == ask_frame * 50 + 10) channel.ask(model, hold);
    const auto& out = session.tick(device);
    if (r.switched_at < 0 && loop.local_model() == model && loop.hold() == hold) r.switched_at = k / 50;
    if (r.switched_at >= 0 && model == LocalModelKind::p && out[0].in_contact)
      r.worst_p_law = std::max(r.worst_p_law, std::abs(out[0].normal_force - loop.gains().proportional * out[0].penetration));
  }
  return r;
}

TEST(ModeSwitch, AnAcceptedSwitchBringsItsOwnRobustGainsAtTheNextFrame) {
  ModeChannel channel;
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi_smith;
  settings.hold = HoldKind::zoh;
  settings.modes = &channel;
  auto environment = LinearSurfaceEnvironment::isotropic({ContactFrame{}}, kStiffness, kDamping);
  HapticLoop loop(settings, initial_update(environment));
  const SwitchRun r = run(loop, environment, channel, LocalModelKind::p, HoldKind::foh, 20, 40);
  const ModeVerdict verdict = channel.verdict();
  EXPECT_EQ(verdict.request, 1);
  ASSERT_TRUE(verdict.accepted) << verdict.text;
  EXPECT_NE(verdict.text.find("p + foh from frame"), std::string::npos) << verdict.text;
  // Asked during frame 20; analysed with the answer to frame 21's samples (taken at its first
  // tick); in force from frame 22's first tick, as the verdict says.
  EXPECT_EQ(r.switched_at, 22);
  EXPECT_NE(verdict.text.find("from frame 22:"), std::string::npos) << verdict.text;
  // The gains it came with are robustly stable for P + FOH on this tissue, as the analysis run
  // here says, and are those it renders with.
  EXPECT_LT(verdict.spectral_radius, 1);
  EXPECT_NEAR(robust_spectral_radius(problem_for(LocalModelKind::p, HoldKind::foh), verdict.gains), verdict.spectral_radius, 1e-9);
  EXPECT_GT(verdict.gains.proportional, 0);
  // P renders F = Kh e: no integrator, no predictor left over from PI + Smith.
  EXPECT_LT(r.worst_p_law, 1e-12);
}

TEST(ModeSwitch, AnUnstableModeIsRefusedWithItsReasonAndNothingChanges) {
  // Fixed gains that PI + Smith renders robustly stable and plain PI does not (found here by the
  // analysis, over Kh from 0.5 to 20 times the tissue's stiffness, N I a tenth of Kh).
  LocalModelGains gains;
  bool found = false;
  for (double ratio = 0.5; ratio <= 20 && !found; ratio *= 1.25) {
    gains = {ratio * kStiffness, 0.1 * ratio * kStiffness / 50};
    found = robust_spectral_radius(problem_for(LocalModelKind::pi_smith, HoldKind::zoh), gains) < 1 &&
            robust_spectral_radius(problem_for(LocalModelKind::pi, HoldKind::zoh), gains) >= 1;
  }
  ASSERT_TRUE(found);
  ModeChannel channel;
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi_smith;
  settings.hold = HoldKind::zoh;
  settings.schedule_gains = false;
  settings.gains = gains;
  settings.modes = &channel;
  auto environment = LinearSurfaceEnvironment::isotropic({ContactFrame{}}, kStiffness, kDamping);
  HapticLoop loop(settings, initial_update(environment));
  const SwitchRun r = run(loop, environment, channel, LocalModelKind::pi, HoldKind::zoh, 5, 20);
  const ModeVerdict verdict = channel.verdict();
  EXPECT_EQ(verdict.request, 1);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(r.switched_at, -1);
  EXPECT_EQ(loop.local_model(), LocalModelKind::pi_smith);
  EXPECT_NEAR(verdict.spectral_radius, robust_spectral_radius(problem_for(LocalModelKind::pi, HoldKind::zoh), gains), 1e-9);
  EXPECT_GE(verdict.spectral_radius, 1);
  EXPECT_NE(verdict.text.find("refused pi + zoh"), std::string::npos) << verdict.text;
  EXPECT_NE(verdict.text.find("pi_smith + zoh stays"), std::string::npos) << verdict.text;
  // The frames after it still carry the old mode and the given gains.
  EXPECT_EQ(loop.newest().local_model, LocalModelKind::pi_smith);
  EXPECT_EQ(loop.gains().proportional, gains.proportional);
}

}  // namespace
}  // namespace fetouch::haptics
