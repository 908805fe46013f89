// On-line identification (identification.h) against contacts whose law is known: a Kelvin-Voigt
// contact sampled as a PHANTOM samples it (0.055 mm encoder steps, 10 mN force noise), a
// Hunt-Crossley contact, and the multirate loop on a linear tissue whose condensed stiffness is
// known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "haptics/contact_frame.h"
#include "haptics/haptic_loop.h"
#include "haptics/identification.h"
#include "haptics/linear_surface_environment.h"

namespace fetouch::haptics {
namespace {

constexpr double kPeriod = 1e-3;
constexpr double kPi = 3.14159265358979323846;
// An Omni/Touch encoder step (reference/passivity-and-identification.md) and a force sensor's noise.
constexpr double kQuantum = 5.5e-5, kForceNoise = 0.01;

// A device pressing along -z into a contact whose force along +z is `law(depth, rate)`, sampled as a
// device samples it: the depth quantised to encoder steps, the rate a 10-tick difference of the
// quantised depth (a device's velocity is filtered too), the force with noise.
struct Bench {
  std::mt19937 random{7};
  std::normal_distribution<double> noise{0, kForceNoise};
  std::vector<double> depths;  // quantised, per tick
  double rate(double depth_quantised) {
    depths.push_back(depth_quantised);
    const std::size_t n = depths.size();
    return n > 10 ? (depths[n - 1] - depths[n - 11]) / (10 * kPeriod) : 0.0;
  }
  static double quantise(double depth) { return kQuantum * std::round(depth / kQuantum); }
};

// The reference's simulation baseline (K0 300 N/m, B0 2 N s/m, palpation 3 +- 2 mm at 2 Hz): the
// stiffness within 5 % in 100 ms of contact and within 2 % after 0.5 s; K0 doubled at 2 s, followed
// within 5 % by 2.5 s; then a still hand held for 2 s: K moves by under 1 %.
TEST(Identification, KelvinVoigtSettlesTracksADoublingAndDoesNotDriftInAHold) {
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(), touch(0.01, 0.02, 0.03);
  ContactIdentifier identifier;
  Bench bench;
  double stiffness = 300;
  const double damping = 2;
  double within_5_at = -1, worst_steady = 0, worst_doubled = 0, before_hold = 0, hold_depth = 0;
  const long ticks = 7000;
  for (long k = 0; k < ticks; ++k) {
    const double t = k * kPeriod;
    if (t >= 2.0) stiffness = 600;
    // Into the contact to 3 mm in 0.1 s, then palpation; from 3 s the hand holds still.
    double depth = t < 0.1 ? 0.03 * t : 3e-3 + 2e-3 * std::sin(2 * kPi * 2 * (t - 0.1));
    if (t >= 3.0) depth = hold_depth;
    else hold_depth = depth;
    const double measured = Bench::quantise(depth), rate = bench.rate(measured);
    const double true_rate = t < 0.1 ? 0.03 : t < 3.0 ? 2e-3 * 2 * kPi * 2 * std::cos(2 * kPi * 2 * (t - 0.1)) : 0.0;
    const double force = stiffness * depth + damping * true_rate + bench.noise(bench.random);
    identifier.update(touch - measured * normal, -rate * normal, normal, force * normal, true);
    const double error = std::abs(identifier.stiffness_n_per_m() - stiffness) / stiffness;
    if (within_5_at < 0 && identifier.valid() && error < 0.05) within_5_at = t;
    if (t > 0.5 && t < 2.0) worst_steady = std::max(worst_steady, error);
    if (t > 2.5 && t < 3.0) worst_doubled = std::max(worst_doubled, error);
    if (k == 3000) before_hold = identifier.stiffness_n_per_m();
  }
  EXPECT_GE(within_5_at, 0);
  EXPECT_LT(within_5_at, 0.1);
  EXPECT_LT(worst_steady, 0.02);
  EXPECT_LT(worst_doubled, 0.05);
  EXPECT_LT(std::abs(identifier.stiffness_n_per_m() - before_hold) / before_hold, 0.01);
  EXPECT_NEAR(identifier.damping_n_s_per_m(), damping, 0.5);  // the 10-tick rate lags: B is the coarser
}

// A steady press (10 mm/s) into a Kelvin-Voigt contact: the stiffness within 5 % in 100 ms, though
// the rate never changes (B and the offset are then not told apart; K is).
TEST(Identification, SteadyPressGivesTheStiffnessWithinAHundredMilliseconds) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.2, 0.93).normalized();
  ContactIdentifier identifier;
  Bench bench;
  double within_5_at = -1, worst_after = 0;
  for (long k = 0; k < 600; ++k) {
    const double t = k * kPeriod, depth = 0.01 * t;
    const double measured = Bench::quantise(depth), rate = bench.rate(measured);
    const double force = 800 * depth + 3 * 0.01 + bench.noise(bench.random);
    identifier.update(-measured * normal, -rate * normal, normal, force * normal, true);
    const double error = std::abs(identifier.stiffness_n_per_m() - 800) / 800;
    if (within_5_at < 0 && identifier.valid() && error < 0.05) within_5_at = t;
    if (t > 0.1) worst_after = std::max(worst_after, error);
  }
  EXPECT_GE(within_5_at, 0);
  EXPECT_LT(within_5_at, 0.1);
  EXPECT_LT(worst_after, 0.05);
}

// A contact that ends and starts again learns afresh from the new contact's depth origin.
TEST(Identification, ANewContactStartsFromItsOwnDepth) {
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  ContactIdentifier identifier;
  for (int contact = 0; contact < 2; ++contact) {
    const double surface = contact == 0 ? 0.0 : -0.004, stiffness = contact == 0 ? 300 : 900;
    for (long k = 0; k < 400; ++k) {
      const double depth = 0.01 * k * kPeriod;
      identifier.update(Eigen::Vector3d(0, 0, surface - depth), Eigen::Vector3d(0, 0, -0.01), normal,
                        stiffness * depth * normal, true);
    }
    EXPECT_TRUE(identifier.valid());
    EXPECT_NEAR(identifier.stiffness_n_per_m(), stiffness, 1e-6 * stiffness);
    EXPECT_NEAR(identifier.offset_n(), 0, 1e-6);
    identifier.update(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), normal, Eigen::Vector3d::Zero(), false);
    EXPECT_FALSE(identifier.in_contact());
  }
}

// Hunt-Crossley f = k x^n + lambda x^n v (k 4000 N/m^1.4, n 1.4, lambda 5 k s/m: the damping part
// is 12 % of the force at 25 mm/s), palpated 4 +- 2 mm at 2 Hz through the same noisy sampling and
// identified from n = 1.5 (Hertz): after 2 s, the force over the next cycle predicted from the
// true depth and rate within 5 % of its peak, and n within 0.05.
TEST(Identification, HuntCrossleyForcePredictedWithinFivePercentOfItsPeak) {
  const double k = 4000, n = 1.4, lambda = 5 * k;
  const auto law = [&](double x, double v) { return x > 0 ? k * std::pow(x, n) + lambda * std::pow(x, n) * v : 0.0; };
  HuntCrossleyIdentifier identifier;
  Bench bench;
  const auto depth_at = [](double t) { return 4e-3 + 2e-3 * std::sin(2 * kPi * 2 * t); };
  const auto rate_at = [](double t) { return 2e-3 * 2 * kPi * 2 * std::cos(2 * kPi * 2 * t); };
  for (long tick = 0; tick < 2000; ++tick) {
    const double t = tick * kPeriod;
    const double measured = Bench::quantise(depth_at(t)), rate = bench.rate(measured);
    identifier.update(measured, rate, law(depth_at(t), rate_at(t)) + bench.noise(bench.random));
  }
  double peak = 0, worst = 0;
  for (long tick = 2000; tick < 2500; ++tick) {
    const double t = tick * kPeriod, truth = law(depth_at(t), rate_at(t));
    peak = std::max(peak, truth);
    worst = std::max(worst, std::abs(identifier.predict_n(depth_at(t), rate_at(t)) - truth));
  }
  EXPECT_LT(worst, 0.05 * peak) << "k " << identifier.stiffness() << " n " << identifier.exponent() << " lambda "
                                << identifier.damping();
  EXPECT_NEAR(identifier.exponent(), n, 0.05);
}

TEST(Identification, SettingsOutOfRangeAreRefusedByName) {
  IdentificationSettings s;
  s.forgetting = 1.2;
  try {
    check(s);
    FAIL() << "accepted a forgetting factor of 1.2";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("forgetting"), std::string::npos);
  }
  s = {};
  s.max_covariance = 1;  // below the initial covariance
  EXPECT_THROW(check(s), std::invalid_argument);
}

// ---- through the multirate loop -----------------------------------------------------------------

struct LoopRun {
  std::vector<double> identified, condensed;
  std::vector<bool> valid;
  IdentificationCheck check;
  double proportional_gain = 0;
};

struct LoopCase {
  LocalModelKind local_model = LocalModelKind::pi_smith;  // the default scene's mode
  HoldKind hold = HoldKind::zoh;
  PassivityMode passivity = PassivityMode::on;
  double doubled_at_s = 1e9;  // the tissue's stiffness doubles at the first solve from then on
};

// One contact on a linear tissue of stiffness `stiffness` (isotropic, no damping; its condensed
// normal stiffness is `stiffness` exactly), gains scheduled, the safety clamp out of the way, and a
// device that `path` moves (depth below the rest surface, m, against time).
LoopRun run_loop(double stiffness, double duration_s, double (*path)(double), const LoopCase& c = {}) {
  std::vector<ContactFrame> rest(1);
  rest[0].point = Eigen::Vector3d(0, 0, 0);
  rest[0].normal = Eigen::Vector3d::UnitZ();
  LinearSurfaceEnvironment environment = LinearSurfaceEnvironment::isotropic(rest, stiffness);
  HapticLoopSettings settings;
  settings.local_model = c.local_model;
  settings.hold = c.hold;
  settings.passivity.mode = c.passivity;
  settings.safety.max_force_n = 50;
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  LoopRun run;
  bool doubled = false;
  const long ticks = std::lround(duration_s / kPeriod);
  for (long k = 0; k < ticks; ++k) {
    const double t = k * kPeriod;
    if (!doubled && t >= c.doubled_at_s) {
      environment.set_stiffness(2 * stiffness * Eigen::MatrixXd::Identity(3, 3));
      doubled = true;
    }
    const double d = path(t), v = (path(t + 1e-6) - path(t - 1e-6)) / 2e-6;
    const ContactOutput& out = session.tick({Eigen::Vector3d(0, 0, -d)}, {Eigen::Vector3d(0, 0, -v)})[0];
    run.identified.push_back(out.identified_stiffness_n_per_m);
    run.condensed.push_back(out.condensed_stiffness_n_per_m);
    run.valid.push_back(out.identified);
  }
  run.check = loop.identification(0);
  run.proportional_gain = loop.gains().proportional;
  return run;
}

double press(double t) { return t < 0.05 ? 0.0 : 0.01 * (t - 0.05); }  // touches at 50 ms, 10 mm/s

// What the hand feels through the default scene's rendering (PI + Smith predictor, ZOH) against
// the tissue's condensed stiffness, known here: W^-1 = K0. A steady press reaches it within 5 %
// within 100 ms of contact and stays there, and no frame disagrees beyond the bound.
TEST(IdentificationInTheLoop, SteadyPressIdentifiesTheCondensedStiffnessWithinAHundredMilliseconds) {
  for (double stiffness : {300.0, 1500.0}) {
    SCOPED_TRACE("K0 " + std::to_string(stiffness) + " N/m");
    const LoopRun run = run_loop(stiffness, 0.6, press);
    EXPECT_NEAR(run.condensed.back(), stiffness, 1e-9 * stiffness);
    long first_within = -1;
    double worst_after = 0;
    for (std::size_t k = 0; k < run.identified.size(); ++k) {
      const double error = std::abs(run.identified[k] - stiffness) / stiffness;
      if (first_within < 0 && run.valid[k] && error < 0.05) first_within = static_cast<long>(k);
      if (first_within >= 0) worst_after = std::max(worst_after, error);
    }
    ASSERT_GE(first_within, 0);
    EXPECT_LE(first_within * kPeriod - 0.05, 0.1);
    EXPECT_LT(worst_after, 0.05);
    EXPECT_GT(run.check.frames_compared, 8);
    EXPECT_EQ(run.check.disagreements, 0);
  }
}

// The P local model renders its spring Kh in series with the tissue: at steady state the hand
// feels Kh K0 / (Kh + K0), far below K0 (the closed form is the independent answer). The
// identification finds that, and every compared frame is reported as a disagreement.
TEST(IdentificationInTheLoop, ThePLocalModelsSeriesSpringIsFeltAndReported) {
  const double stiffness = 300;
  LoopCase p;
  p.local_model = LocalModelKind::p;
  p.hold = HoldKind::foh;
  const LoopRun run = run_loop(stiffness, 0.6, press, p);
  const double series = run.proportional_gain * stiffness / (run.proportional_gain + stiffness);
  EXPECT_LT(series, 0.5 * stiffness);
  EXPECT_NEAR(run.identified.back(), series, 0.02 * series);
  EXPECT_GT(run.check.frames_compared, 8);
  EXPECT_EQ(run.check.disagreements, run.check.frames_compared);
}

double palpate(double t) {  // touches at 50 ms, eases to 3 mm over 0.5 s, then 3 +- 1 mm at 2 Hz
  if (t < 0.05) return 0;
  t -= 0.05;
  return t < 0.5 ? 1.5e-3 * (1 - std::cos(kPi * t / 0.5)) : 3e-3 + 1e-3 * std::sin(2 * kPi * 2 * (t - 0.5));
}

// The tissue doubles its stiffness under a palpating hand: the identification is within 5 % of
// the new value within 0.5 s of the first frame that renders it. The layer only observes here: a
// spring stiffened under the hand and then released hands the hand energy, and with the layer on
// the contact is scaled (what the hand then feels is s times the tissue, which the identification
// reports as a disagreement; docs/stability.md).
TEST(IdentificationInTheLoop, ADoubledStiffnessIsTrackedWithinHalfASecond) {
  const double stiffness = 400;
  LoopCase c;
  c.passivity = PassivityMode::observe;
  c.doubled_at_s = 1.5;
  const LoopRun run = run_loop(stiffness, 2.5, palpate, c);
  std::size_t felt = 0;  // the first tick whose frame renders the doubled tissue
  while (felt < run.condensed.size() && run.condensed[felt] < 1.5 * stiffness) ++felt;
  ASSERT_LT(felt, run.condensed.size());
  double worst_before = 0, worst_after = 0;
  for (std::size_t k = 0; k < run.identified.size(); ++k) {
    const double t = k * kPeriod;
    if (t > 0.6 && k < felt) worst_before = std::max(worst_before, std::abs(run.identified[k] - stiffness) / stiffness);
    if (k >= felt + 500) worst_after = std::max(worst_after, std::abs(run.identified[k] - 2 * stiffness) / (2 * stiffness));
  }
  EXPECT_LT(worst_before, 0.05);
  EXPECT_LT(worst_after, 0.05);
  EXPECT_GT(run.check.disagreements, 0);   // the frames while it caught up
  EXPECT_LE(run.check.disagreements, 10);  // and no more (10 frames: 0.5 s)
}

double press_and_hold(double t) { return t < 0.05 ? 0.0 : t < 0.35 ? 0.01 * (t - 0.05) : 3e-3; }

// A press, then the hand held still for 2 s: the identified stiffness stays where the press left it.
TEST(IdentificationInTheLoop, AStaticHoldDoesNotDrift) {
  const double stiffness = 600;
  const LoopRun run = run_loop(stiffness, 2.4, press_and_hold);
  const double at_hold = run.identified[350];
  double worst = 0;
  for (std::size_t k = 350; k < run.identified.size(); ++k) worst = std::max(worst, std::abs(run.identified[k] - at_hold));
  EXPECT_LT(worst, 0.01 * at_hold);
  EXPECT_NEAR(at_hold, stiffness, 0.05 * stiffness);
}

}  // namespace
}  // namespace fetouch::haptics
