// Devices without hardware: trajectories read from CSV (and refused with file:line when broken),
// resampled by linear interpolation; the replay device; the virtual operator against the closed
// forms of a mass-spring-damper (undamped step response, static deflection under a force, tracking
// of a ramp).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>

#include "haptics/devices.h"

namespace fetouch::haptics {
namespace {

namespace fs = std::filesystem;

fs::path write_csv(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("fetouch_traj_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(Trajectory, ReadsCsvAndInterpolates) {
  const auto path = write_csv("ok.csv", "# a comment\nt_s,x_m,y_m,z_m\n0,0,0,0.06\n0.5, 0, 0, 0.05\n1.5,0.01,0,0.05\n");
  const Trajectory t = read_trajectory_csv(path);
  ASSERT_EQ(t.times_s.size(), 3u);
  EXPECT_DOUBLE_EQ(t.duration_s(), 1.5);
  EXPECT_NEAR(t.at(0.25).z(), 0.055, 1e-15);
  EXPECT_NEAR(t.at(1.0).x(), 0.005, 1e-15);
  EXPECT_EQ(t.at(-1), t.positions_m.front());
  EXPECT_EQ(t.at(9), t.positions_m.back());
  const auto ticks = t.resampled(1e-3);
  ASSERT_EQ(ticks.size(), 1501u);  // 0, 1 ms, ..., 1.5 s
  EXPECT_NEAR(ticks[250].z(), 0.055, 1e-15);
  EXPECT_NEAR(ticks[1500].x(), 0.01, 1e-15);
  // Written and read again: the same numbers.
  write_trajectory_csv(t, path, "round trip");
  const Trajectory back = read_trajectory_csv(path);
  EXPECT_EQ(back.times_s, t.times_s);
  for (std::size_t i = 0; i < t.positions_m.size(); ++i) EXPECT_EQ(back.positions_m[i], t.positions_m[i]);
  fs::remove(path);
}

TEST(Trajectory, BrokenFilesNameTheLine) {
  const auto refused = [](const std::string& name, const std::string& text, const std::string& where) {
    const auto path = write_csv(name, text);
    try {
      read_trajectory_csv(path);
      ADD_FAILURE() << name << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string() + where), std::string::npos) << e.what();
    }
    fs::remove(path);
  };
  refused("three.csv", "t,x,y,z\n0,0,0,0\n1,2,3\n", ":3:");
  refused("word.csv", "0,0,0,0\n1,0,zero,0\n", ":2:");
  refused("back.csv", "0,0,0,0\n1,0,0,0\n0.5,0,0,0\n", ":3:");
  refused("nan.csv", "0,0,0,0\n1,nan,0,0\n", ":2:");
  refused("one.csv", "t,x,y,z\n0,0,0,0\n", ": a trajectory needs at least two rows");
  refused("long.csv", "0,0,0,0\n100000,0,0,0\n", ": lasts 100000");     // 10^5 s: 10^8 ticks (issue 17)
  refused("far.csv", "0,0,0,0\n1,50,0,0\n", ": sample 1: a point 50");  // millimetres written as metres
  EXPECT_THROW(read_trajectory_csv("/nonexistent/path.csv"), std::runtime_error);
}

// Special files hung the replay (issue 17): a FIFO blocks its reader until a writer comes, and a
// device like /dev/zero never ends. Both are refused at once, without opening them.
TEST(Trajectory, OnlyRegularFilesAreRead) {
  const fs::path fifo = fs::temp_directory_path() / ("fetouch_fifo_" + std::to_string(::getpid()) + ".csv");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const fs::path& special : {fifo, fs::path("/dev/zero"), fs::temp_directory_path()}) {
    try {
      read_trajectory_csv(special);
      ADD_FAILURE() << special << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  fs::remove(fifo);
}

// The same checks for a trajectory made in memory (a recording's positions).
TEST(Trajectory, CheckRefusesRepeatedTimesAndNaN) {
  Trajectory t;
  t.times_s = {0, 0.001, 0.001};
  t.positions_m.assign(3, Eigen::Vector3d::Zero());
  EXPECT_THROW(t.check("recording"), std::runtime_error);
  t.times_s = {0, 0.001, 0.002};
  EXPECT_NO_THROW(t.check("recording"));
  t.positions_m[1].y() = std::nan("");
  try {
    t.check("rec.h5");
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("rec.h5: sample 1 is not finite"), std::string::npos) << e.what();
  }
}

TEST(ReplayDevice, PlaysTheResampledPathWhateverTheForce) {
  Trajectory t;
  t.times_s = {0, 0.01};
  t.positions_m = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, -0.01)};
  ReplayDevice device(t, 1e-3);
  EXPECT_EQ(device.ticks(), 11);
  for (int k = 0; k <= 10; ++k) EXPECT_NEAR(device.next(Eigen::Vector3d(0, 0, 5)).z(), -0.001 * k, 1e-15) << k;
  EXPECT_TRUE(device.finished());
  EXPECT_NEAR(device.next(Eigen::Vector3d::Zero()).z(), -0.01, 1e-15);  // held at the end
}

// A target that steps by 1 cm at the first tick.
Trajectory step_target(double seconds) {
  Trajectory t;
  t.times_s = {0, 1e-3, seconds};
  t.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 0.01), Eigen::Vector3d(0, 0, 0.01)};
  return t;
}

TEST(VirtualOperator, UndampedStepIsACosine) {
  // m x'' = k (x_t - x) with x_t = 1 cm from t = T: x(t) = 1 cm (1 - cos w (t - T)), w = sqrt(k/m).
  // The discretisation is exact for inputs held over a tick, so it matches to rounding.
  const HandParameters hand{0.3, 300, 0};
  VirtualOperator op(step_target(1.0), hand, 1e-3);
  const double w = std::sqrt(300 / 0.3);
  double worst = 0;
  for (int k = 0; k <= 1000; ++k) {
    const double z = op.next(Eigen::Vector3d::Zero()).z();
    const double expected = k == 0 ? 0 : 0.01 * (1 - std::cos(w * (k - 1) * 1e-3));
    worst = std::max(worst, std::abs(z - expected));
  }
  EXPECT_LT(worst, 1e-14);
}

TEST(VirtualOperator, ForceFedBackDeflectsTheHandByForceOverStiffness) {
  // Held still at the target with 3 N pushing up: the hand settles at x_t + F / k = +1 cm.
  Trajectory still;
  still.times_s = {0, 5};
  still.positions_m = {Eigen::Vector3d(0.02, 0, 0), Eigen::Vector3d(0.02, 0, 0)};
  VirtualOperator op(still, HandParameters{0.3, 300, 8}, 1e-3);
  Eigen::Vector3d x;
  for (int k = 0; k < 5000; ++k) x = op.next(Eigen::Vector3d(0, 0, 3));
  EXPECT_NEAR(x.z(), 3.0 / 300, 1e-9);
  EXPECT_NEAR(x.x(), 0.02, 1e-12);
  // A force that is not finite is not applied.
  const Eigen::Vector3d before = x;
  x = op.next(Eigen::Vector3d(0, 0, std::nan("")));
  EXPECT_TRUE(x.allFinite());
  EXPECT_NEAR(x.z(), before.z(), 1e-4);
}

TEST(VirtualOperator, TracksARampWithAtMostHalfATickOfLag) {
  // x_t = c t, v_t = c: x = c t solves m x'' = k (x_t - x) + b (v_t - v); holding the input over
  // each tick delays it by T / 2 at most once the start has died away.
  const double c = 0.02;  // m/s
  Trajectory ramp;
  ramp.times_s = {0, 3};
  ramp.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(c * 3, 0, 0)};
  VirtualOperator op(ramp, HandParameters{0.3, 300, 8}, 1e-3);
  Eigen::Vector3d x;
  for (int k = 0; k <= 2000; ++k) x = op.next(Eigen::Vector3d::Zero());
  EXPECT_NEAR(x.x(), c * 2.0, c * 1e-3);
  EXPECT_LE(x.x(), c * 2.0 + 1e-12);
}

// Released at 0.5 s while moving: nothing pulls or damps it any more, so with no force it flies on
// at the speed it had, x(t) = x(t_r) + v(t_r) (t - t_r) (to rounding).
TEST(VirtualOperator, ReleasedHandFliesOnAtItsSpeed) {
  Trajectory ramp;
  ramp.times_s = {0, 2};
  ramp.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.04)};  // -20 mm/s
  HandEvent release;
  release.kind = HandEventKind::release;
  release.at_s = 0.5;
  VirtualOperator op(ramp, HandParameters{0.3, 300, 8}, 1e-3, {release});
  DeviceState at_release;
  for (int k = 0; k <= 500; ++k) at_release = op.read();  // tick 500 integrated the last held grip
  double worst = 0;
  for (int k = 501; k <= 1500; ++k) {
    const DeviceState s = op.read();
    const double expected = at_release.position_m.z() + at_release.velocity_m_per_s.z() * (k - 500) * 1e-3;
    worst = std::max(worst, std::abs(s.position_m.z() - expected));
  }
  EXPECT_LT(worst, 1e-13);
}

// A grip tightened x3 over 10 ms: held still against 3 N, the hand's deflection F / k shrinks to a
// third (from 10 mm to 3.33 mm).
TEST(VirtualOperator, TighterGripDeflectsByForceOverTheNewStiffness) {
  Trajectory still;
  still.times_s = {0, 6};
  still.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  HandEvent grip;
  grip.kind = HandEventKind::grip;
  grip.at_s = 3;
  grip.factor = 3;
  VirtualOperator op(still, HandParameters{0.3, 300, 8}, 1e-3, {grip});
  Eigen::Vector3d x;
  for (int k = 0; k < 3000; ++k) x = op.next(Eigen::Vector3d(0, 0, 3));
  EXPECT_NEAR(x.z(), 3.0 / 300, 1e-6);
  for (int k = 3000; k < 6000; ++k) x = op.next(Eigen::Vector3d(0, 0, 3));
  EXPECT_NEAR(x.z(), 3.0 / 900, 1e-6);
}

// Tremor at f moves the target by A sin(w t); the hand (m x'' + b x' + k x = k x_t + b x_t')
// follows with the gain |k + i w b| / |k - m w^2 + i w b|, reached once the start has died away.
TEST(VirtualOperator, TremorReachesTheHandThroughItsTransferFunction) {
  Trajectory still;
  still.times_s = {0, 4};
  still.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  HandEvent tremor;
  tremor.kind = HandEventKind::tremor;
  tremor.frequency_hz = 10;
  tremor.amplitude_m = 2e-4;
  tremor.direction = Eigen::Vector3d(0, 0, 2);  // normalised on use
  const double m = 0.3, k = 300, b = 8, w = 2 * M_PI * 10;
  VirtualOperator op(still, HandParameters{m, k, b}, 1e-3, {tremor});
  double peak = 0;
  for (int t = 0; t <= 4000; ++t) {
    const double z = op.read().position_m.z();
    if (t > 3000) peak = std::max(peak, std::abs(z));
  }
  const double gain = std::abs(std::complex<double>(k, w * b)) / std::abs(std::complex<double>(k - m * w * w, w * b));
  // 1 % : sampling the peak at 1 kHz (cos(w T / 2) = 0.9995) and the central-difference target
  // velocity (sin(w T) / (w T) = 0.9993) are both far inside it.
  EXPECT_NEAR(peak, gain * 2e-4, 0.01 * gain * 2e-4);
}

TEST(VirtualOperator, ImpactSetsTheHandsSpeed) {
  HandEvent impact;
  impact.kind = HandEventKind::impact;
  impact.at_s = 0.2;
  impact.speed_m_per_s = 0.2;
  VirtualOperator op(step_target(1.0), HandParameters{0.3, 300, 8}, 1e-3, {impact});
  DeviceState s;
  for (int k = 0; k <= 200; ++k) s = op.read();
  EXPECT_NEAR(s.velocity_m_per_s.z(), -0.2, 1e-15);
  EXPECT_NEAR(s.velocity_m_per_s.x(), 0, 1e-15);
}

// The stylus grip (Fu & Cavusoglu's two stages) against a second method: the same equations
// integrated by classical Runge-Kutta at 1/200 of a tick, with the force and the target held over
// each tick as the device holds them. A force that changes every tick and a target that moves.
TEST(VirtualOperatorStylus, MatchesRungeKuttaOfTheTwoStageEquations) {
  const HandParameters hand = stylus_hand();
  Trajectory path;
  path.times_s = {0, 0.3, 1};
  path.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.006), Eigen::Vector3d(0.004, 0, -0.006)};
  const double T = 1e-3;
  VirtualOperator op(path, hand, T);
  const std::vector<Eigen::Vector3d> targets = path.resampled(T);
  const auto force_at = [](int k) { return Eigen::Vector3d(0.3 * std::sin(0.05 * k), 0, 1.5 * (1 - std::cos(0.02 * k))); };
  // Per axis: y = (x_d, v_d, x_h, v_h).
  const auto rate = [&](const Eigen::Vector4d& y, double f, double xt, double vt) {
    const double k1 = hand.stiffness_n_per_m, b1 = hand.damping_n_s_per_m;
    const double k2 = hand.arm_stiffness_n_per_m, b2 = hand.arm_damping_n_s_per_m;
    const double grip = k1 * (y[2] - y[0]) + b1 * (y[3] - y[1]);
    return Eigen::Vector4d(y[1], (grip + f) / hand.handle_mass_kg, y[3],
                           (-grip + k2 * (xt - y[2]) + b2 * (vt - y[3])) / hand.mass_kg);
  };
  std::array<Eigen::Vector4d, 3> y;
  for (int d = 0; d < 3; ++d) y[d] = Eigen::Vector4d(targets[0][d], 0, targets[0][d], 0);
  double worst = 0, largest = 0;
  op.read();  // tick 0: at rest on the first point
  for (int k = 0; k + 1 < static_cast<int>(targets.size()); ++k) {
    const Eigen::Vector3d f = force_at(k);
    op.write(f);
    const Eigen::Vector3d x = op.read().position_m;
    const Eigen::Vector3d vt = (targets[k + 1 == static_cast<int>(targets.size()) ? k : k + 1] - targets[k == 0 ? 0 : k - 1]) /
                               ((k == 0 ? 1.0 : 2.0) * T);
    const int substeps = 200;
    const double h = T / substeps;
    for (int d = 0; d < 3; ++d) {
      for (int s = 0; s < substeps; ++s) {
        const Eigen::Vector4d a = rate(y[d], f[d], targets[k][d], vt[d]);
        const Eigen::Vector4d b = rate(y[d] + h / 2 * a, f[d], targets[k][d], vt[d]);
        const Eigen::Vector4d c = rate(y[d] + h / 2 * b, f[d], targets[k][d], vt[d]);
        const Eigen::Vector4d e = rate(y[d] + h * c, f[d], targets[k][d], vt[d]);
        y[d] += h / 6 * (a + 2 * b + 2 * c + e);
      }
      worst = std::max(worst, std::abs(x[d] - y[d][0]));
      largest = std::max(largest, std::abs(y[d][0]));
    }
  }
  EXPECT_GT(largest, 0.005);       // the handle moved millimetres
  EXPECT_LT(worst, 1e-9 * largest);
}

// Held still against a steady force F, the two stages deflect in series: the handle settles at
// x_t + F (1/k1 + 1/k2); a grip tightened x3 (k1 only) leaves x_t + F (1/(3 k1) + 1/k2).
TEST(VirtualOperatorStylus, StagesDeflectInSeriesAndAGripTightensTheFirst) {
  const HandParameters hand = stylus_hand();
  Trajectory still;
  still.times_s = {0, 12};
  still.positions_m = {Eigen::Vector3d(0, 0, 0.05), Eigen::Vector3d(0, 0, 0.05)};
  HandEvent grip;
  grip.kind = HandEventKind::grip;
  grip.at_s = 6;
  grip.factor = 3;
  VirtualOperator op(still, hand, 1e-3, {grip});
  const double f = 2, k1 = hand.stiffness_n_per_m, k2 = hand.arm_stiffness_n_per_m;
  Eigen::Vector3d x;
  for (int k = 0; k < 6000; ++k) x = op.next(Eigen::Vector3d(0, 0, f));
  EXPECT_NEAR(x.z(), 0.05 + f * (1 / k1 + 1 / k2), 1e-8);
  for (int k = 0; k < 5999; ++k) x = op.next(Eigen::Vector3d(0, 0, f));
  EXPECT_NEAR(x.z(), 0.05 + f * (1 / (3 * k1) + 1 / k2), 1e-8);
}

// Released, the fingers let go of the handle: the force alone moves the device's own mass,
// x(t) = x_r + v_r t + F t^2 / (2 m_d) (to rounding), whatever the arm behind it does.
TEST(VirtualOperatorStylus, ReleasedHandleMovesAsItsOwnMassUnderTheForce) {
  const HandParameters hand = stylus_hand();
  Trajectory still;
  still.times_s = {0, 2};
  still.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  HandEvent release;
  release.kind = HandEventKind::release;
  release.at_s = 0.5;
  VirtualOperator op(still, hand, 1e-3, {release});
  const double f = 0.5;
  DeviceState at_release;
  for (int k = 0; k <= 500; ++k) {
    op.write(Eigen::Vector3d(0, 0, f));
    at_release = op.read();
  }
  double worst = 0;
  for (int k = 501; k <= 700; ++k) {
    op.write(Eigen::Vector3d(0, 0, f));
    const DeviceState s = op.read();
    const double t = (k - 500) * 1e-3;
    const double expected = at_release.position_m.z() + at_release.velocity_m_per_s.z() * t + f * t * t / (2 * hand.handle_mass_kg);
    worst = std::max(worst, std::abs(s.position_m.z() - expected));
  }
  EXPECT_LT(worst, 1e-12);
  HandParameters bad = stylus_hand();
  bad.handle_mass_kg = 0;
  EXPECT_THROW(VirtualOperator(still, bad, 1e-3), std::invalid_argument);
  bad = stylus_hand();
  bad.arm_damping_n_s_per_m = -1;
  EXPECT_THROW(VirtualOperator(still, bad, 1e-3), std::invalid_argument);
  EXPECT_THROW(CursorOperator(Eigen::Vector3d::Zero(), stylus_hand(), 1e-3), std::invalid_argument);
}

TEST(VirtualOperator, RefusesANonPhysicalHand) {
  EXPECT_THROW(VirtualOperator(step_target(1), HandParameters{0, 300, 8}, 1e-3), std::invalid_argument);
  EXPECT_THROW(VirtualOperator(step_target(1), HandParameters{0.3, -1, 8}, 1e-3), std::invalid_argument);
  EXPECT_THROW(VirtualOperator(step_target(1), HandParameters{0.3, 300, -1}, 1e-3), std::invalid_argument);
  HandEvent bad;
  bad.kind = HandEventKind::grip;
  bad.factor = 0;
  EXPECT_THROW(VirtualOperator(step_target(1), HandParameters{}, 1e-3, {bad}), std::invalid_argument);
  bad.kind = HandEventKind::impact;
  bad.direction.setZero();
  EXPECT_THROW(VirtualOperator(step_target(1), HandParameters{}, 1e-3, {bad}), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::haptics

namespace fetouch::haptics {
namespace {

TEST(ScriptedPath, PokeSlideAndSqueezeFollowTheirPhases) {
  PathSettings s;
  s.point = Eigen::Vector3d(0.01, 0.02, 0.03);
  s.normal = Eigen::Vector3d(0, 0, 2);  // normalised inside
  s.slide_m = Eigen::Vector3d(0.02, 0, 0);
  s.approach_m = 0.01, s.depth_m = 0.005;
  s.approach_s = 0.4, s.press_s = 0.6, s.hold_s = 1.0, s.release_s = 0.5, s.retreat_s = 0.5;
  const Trajectory poke = scripted_path(PathShape::poke, s);
  ASSERT_EQ(poke.times_s, (std::vector<double>{0, 0.4, 1.0, 2.0, 2.5, 3.0}));
  EXPECT_TRUE(poke.at(0).isApprox(Eigen::Vector3d(0.01, 0.02, 0.04)));
  EXPECT_TRUE(poke.at(0.4).isApprox(s.point));
  EXPECT_TRUE(poke.at(1.5).isApprox(Eigen::Vector3d(0.01, 0.02, 0.025)));  // held 5 mm deep
  EXPECT_TRUE(poke.at(0.7).isApprox(Eigen::Vector3d(0.01, 0.02, 0.0275)));  // halfway down
  const Trajectory slide = scripted_path(PathShape::slide, s);
  EXPECT_TRUE(slide.at(1.5).isApprox(Eigen::Vector3d(0.02, 0.02, 0.025)));  // halfway along, pressed
  EXPECT_TRUE(slide.at(3.0).isApprox(Eigen::Vector3d(0.03, 0.02, 0.04)));
  EXPECT_TRUE(scripted_path(PathShape::squeeze, s).at(1.5).isApprox(poke.at(1.5)));
  s.hold_s = 0;
  EXPECT_THROW(scripted_path(PathShape::poke, s), std::invalid_argument);
}

// The mouse's hand model: pulled to a cursor moved from another thread, it settles where its spring
// balances the force it is sent, target + F / k (a closed form), and follows a new target.
TEST(CursorOperator, SettlesWhereItsSpringBalancesTheForceAndFollowsTheCursor) {
  const HandParameters hand{0.1, 200, 9};
  CursorOperator cursor(Eigen::Vector3d(0, 0, 0.05), hand, 1e-3);
  EXPECT_FALSE(cursor.finished());
  EXPECT_EQ(cursor.ticks(), -1);
  const Eigen::Vector3d force(0, 0, 0.8);
  cursor.set_target(Eigen::Vector3d(0.01, 0, 0.03));
  Eigen::Vector3d p;
  for (int k = 0; k < 3000; ++k) p = cursor.next(force);
  EXPECT_NEAR(p.x(), 0.01, 1e-9);
  EXPECT_NEAR(p.z(), 0.03 + 0.8 / 200, 1e-9);
  // A target set between ticks is taken at the next read; a NaN force is ignored.
  cursor.set_target(Eigen::Vector3d(0, 0.02, 0));
  for (int k = 0; k < 3000; ++k) p = cursor.next(Eigen::Vector3d::Constant(std::nan("")));
  EXPECT_NEAR((p - Eigen::Vector3d(0, 0.02, 0)).norm(), 0, 1e-9);
  EXPECT_THROW(CursorOperator(Eigen::Vector3d::Zero(), HandParameters{0, 200, 9}, 1e-3), std::invalid_argument);
}

}  // namespace
}  // namespace fetouch::haptics
