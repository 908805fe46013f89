// The 3D haptic loop through the Environment seam, against independent answers: the scalar loop in
// normal coordinates (the seed's diagram), sphere geometry, closed-form stability of a coupled pair.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "haptics/contact_frame.h"
#include "haptics/haptic_loop.h"
#include "haptics/linear_surface_environment.h"
#include "haptics/normal_loop.h"
#include "haptics/stability_analysis.h"

namespace fetouch::haptics {
namespace {

TEST(ContactFrame, TangentBasisIsOrthonormalAndRightHanded) {
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.3, -0.8, 0.52).normalized(),
                                  Eigen::Vector3d(-0.59, 0.59, 0.55).normalized()}) {
    const auto t = tangent_basis(n);
    EXPECT_NEAR(t.col(0).norm(), 1, 1e-15);
    EXPECT_NEAR(t.col(1).norm(), 1, 1e-15);
    EXPECT_NEAR(t.col(0).dot(n), 0, 1e-15);
    EXPECT_NEAR(t.col(0).dot(t.col(1)), 0, 1e-15);
    EXPECT_NEAR((t.col(0).cross(t.col(1)) - n).norm(), 0, 1e-15);
  }
}

// A sphere of radius R seen near its north pole is the quadric C = I / R: the penetration differs
// from the exact R - |p - centre| by O(|u|^4 / R^3), and the surface point lies on the sphere to
// the same order.
TEST(ContactFrame, QuadricMatchesASphereToFourthOrder) {
  const double radius = 0.05;
  const Eigen::Vector3d normal = Eigen::Vector3d(0.2, -0.4, 0.9).normalized(), centre(0.01, 0.02, -0.03);
  ContactFrame frame;
  frame.point = centre + radius * normal;
  frame.normal = normal;
  frame.curvature = Eigen::Matrix2d::Identity() / radius;
  const auto t = tangent_basis(normal);
  for (double r : {1e-3, 2e-3, 4e-3})
    for (double depth : {-1e-3, 0.0, 2e-3}) {
      const Eigen::Vector3d device = frame.point + t * Eigen::Vector2d(r * 0.6, -r * 0.8) - depth * normal;
      const ContactPoint c = locate(frame, device);
      const double exact = radius - (device - centre).norm();
      const double bound = 2 * std::pow(r, 4) / std::pow(radius, 3) + 2 * std::abs(depth) * r * r / (radius * radius);
      EXPECT_NEAR(c.penetration, exact, bound) << r << " " << depth;
      EXPECT_NEAR((c.surface_point - centre).norm(), radius, bound) << r;
    }
}

// Two contacts on differently oriented surfaces of a coupled, anisotropic tissue, B0 = 0.2 K0:
// projected on the normals it is the loop in normal coordinates (normal_loop.h: contacts on one
// plane, the tissue given along the normals only) with K_n = (N' K0^-1 N)^-1 and B_n = 0.2 K_n.
// With fixed gains, the 3D loop's normal forces equal those of the loop the analysis lifts, for
// every model and hold: the orientation, the tangential wander and the tangential stiffness do not
// enter.
TEST(HapticLoop, ProjectsOntoTheNormalCoordinateLoop) {
  const Eigen::Vector3d n0 = Eigen::Vector3d(0, 0, 1), n1 = Eigen::Vector3d(0.6, 0, 0.8);
  std::vector<ContactFrame> rest(2);
  rest[0].point = {0, 0, 0}, rest[0].normal = n0;
  rest[1].point = {0.03, 0, -0.01}, rest[1].normal = n1;
  Eigen::MatrixXd k0(6, 6);
  k0.setIdentity();
  k0 *= 500;
  k0.block<3, 3>(0, 3) = k0.block<3, 3>(3, 0) = -150 * Eigen::Matrix3d::Identity();
  k0(2, 2) += 100, k0(0, 0) += 50;  // anisotropic
  Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(6, 2);
  normals.block<3, 1>(0, 0) = n0, normals.block<3, 1>(3, 1) = n1;
  const Eigen::MatrixXd wn = normals.transpose() * k0.inverse() * normals, kn = wn.inverse();

  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith})
    for (HoldKind hold : {HoldKind::zoh, HoldKind::foh}) {
      HapticLoopSettings settings;
      settings.local_model = kind;
      settings.hold = hold;
      settings.schedule_gains = false;
      settings.gains = {120, has_integrator(kind) ? 60.0 / 50 : 0.0};
      settings.safety.max_force_n = 1e9, settings.safety.max_force_rate_n_per_s = 1e12;
      settings.passivity.mode = PassivityMode::off;  // the loop the analysis lifts: no hand, no layer
      LinearSurfaceEnvironment environment(rest, k0, 0.2 * k0);
      HapticLoop loop(settings, initial_update(environment));
      LockstepSession session(loop, environment);

      LoopParameters p;
      p.local_model = kind, p.hold = hold, p.ratio = 50, p.stiffness = kn, p.damping = 0.2 * kn;
      p.gains = settings.gains;
      p.compliance = wn;
      NormalLoop scalar = make_loop(p);

      std::vector<Eigen::Vector3d> devices(2);
      Eigen::VectorXd depth(2);
      double worst = 0, largest = 0;
      for (int k = 0; k < 50 * 40; ++k) {
        // Depths 2..6 mm, always in contact; a tangential wander that planes must ignore.
        const double s = k * 1e-3;
        depth << 0.004 + 0.002 * std::sin(3 * s), 0.003 + 0.001 * std::cos(5 * s);
        devices[0] = rest[0].point - depth(0) * n0 + Eigen::Vector3d(0.01 * std::sin(s), 0.002, 0);
        devices[1] = rest[1].point - depth(1) * n1 + Eigen::Vector3d(0, 0.01 * std::cos(2 * s), 0);
        const auto& out = session.tick(devices);
        const Eigen::VectorXd& expected = scalar.tick(depth);
        for (int c = 0; c < 2; ++c) {
          ASSERT_TRUE(out[c].in_contact);
          worst = std::max(worst, std::abs(out[c].normal_force - expected(c)));
          largest = std::max(largest, std::abs(expected(c)));
          EXPECT_NEAR((out[c].force - out[c].normal_force * rest[c].normal).norm(), 0, 1e-9);
        }
      }
      // Round-off only: the two geometries add the same terms in different orders.
      EXPECT_LT(worst, 1e-10 * largest) << static_cast<int>(kind) << "/" << static_cast<int>(hold);
      EXPECT_GT(largest, 0.5);
    }
}

struct PressRun {
  std::vector<double> force;       // normal force per tick, contact 0
  std::vector<Eigen::Vector3d> proxy;
  std::vector<char> contact;
};

// A press and release of one contact on an isotropic tissue: the device comes down from 2 mm
// above the surface to 4 mm inside and back, twice, over `seconds`.
PressRun press_twice(HapticLoopSettings settings, double seconds, double stiffness = 400) {
  ContactFrame rest;
  auto environment = LinearSurfaceEnvironment::isotropic({rest}, stiffness, 20);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  PressRun run;
  std::vector<Eigen::Vector3d> device(1);
  const int ticks = static_cast<int>(seconds / settings.period_s);
  for (int k = 0; k < ticks; ++k) {
    const double phase = 2 * M_PI * 2 * k / ticks;  // two presses
    device[0] = Eigen::Vector3d(0.001, 0, 0.002 - 0.003 * (1 - std::cos(phase)));
    const auto& out = session.tick(device);
    run.force.push_back(out[0].normal_force);
    run.proxy.push_back(out[0].proxy);
    run.contact.push_back(out[0].in_contact);
  }
  return run;
}

// Onset and release without force steps: the force enters and leaves contact through zero, for
// every local model (FOH; gains scheduled). A step would show as a first or last contact force of
// the order of the peak; smooth contact makes it the change of one tick, under 1 % of the peak.
TEST(HapticLoop, ContactOnsetAndReleaseWithoutForceSteps) {
  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith}) {
    HapticLoopSettings settings;
    settings.local_model = kind;
    settings.hold = HoldKind::foh;
    const PressRun run = press_twice(settings, 8.0);
    const double peak = *std::max_element(run.force.begin(), run.force.end());
    ASSERT_GT(peak, 0.15) << static_cast<int>(kind);
    int onsets = 0, releases = 0;
    for (size_t k = 1; k < run.force.size(); ++k) {
      if (run.contact[k] && !run.contact[k - 1]) {
        ++onsets;
        EXPECT_LT(run.force[k], 0.01 * peak) << "onset at tick " << k << ", model " << static_cast<int>(kind);
      }
      if (!run.contact[k] && run.contact[k - 1]) {
        ++releases;
        EXPECT_LT(run.force[k - 1], 0.01 * peak) << "release at tick " << k << ", model " << static_cast<int>(kind);
      }
    }
    EXPECT_EQ(onsets, 2) << static_cast<int>(kind);
    EXPECT_EQ(releases, 2) << static_cast<int>(kind);
  }
}

// The proxy of a P local model lies on the held surface (a plane moving along z here): in contact,
// its z equals the held surface's, which the device is below.
TEST(HapticLoop, ProxyStaysOnTheHeldSurface) {
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::p;
  settings.hold = HoldKind::zoh;
  settings.schedule_gains = false;
  settings.gains = {300, 0};
  ContactFrame rest;
  rest.curvature = Eigen::Matrix2d::Identity() / 0.04;  // a dome of radius 4 cm
  auto environment = LinearSurfaceEnvironment::isotropic({rest}, 400, 0);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0.004, -0.002, -0.003)};
  for (int k = 0; k < 50 * 20; ++k) {
    const auto& out = session.tick(device);
    const ContactFrame& held = loop.newest().update.frames[0];
    ASSERT_TRUE(out[0].in_contact);
    // On the quadric of the held frame, directly above the device along the normal.
    const auto t = tangent_basis(held.normal);
    const Eigen::Vector2d u = t.transpose() * (out[0].proxy - held.point);
    EXPECT_NEAR(held.normal.dot(out[0].proxy - held.point), -0.5 * u.dot(held.curvature * u), 1e-15);
    EXPECT_NEAR((t.transpose() * (out[0].proxy - device[0])).norm(), 0, 1e-15);
  }
}

TEST(HapticLoop, SameInputsGiveBitIdenticalOutputs) {
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi;  // FOH, gains scheduled every frame
  const PressRun a = press_twice(settings, 3.0), b = press_twice(settings, 3.0);
  ASSERT_EQ(a.force.size(), b.force.size());
  EXPECT_EQ(std::memcmp(a.force.data(), b.force.data(), a.force.size() * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(a.proxy.data(), b.proxy.data(), a.proxy.size() * sizeof(Eigen::Vector3d)), 0);
}

// Two contacts pressing one soft coupled tissue (normal stiffness [[1, -0.8], [-0.8, 1]] x 500 N/m):
// a fixed Kh = 150 N/m, fine for each contact alone (Kh < K0), diverges together (soft mode 100 N/m);
// with gain scheduling the loop selects gains for the soft mode and settles.
TEST(HapticLoop, CoupledContactsAreScheduledOnTheirSoftMode) {
  std::vector<ContactFrame> rest(2);
  rest[1].point = {0.02, 0, 0};
  Eigen::MatrixXd k0 = Eigen::MatrixXd::Identity(6, 6) * 500;
  k0(2, 5) = k0(5, 2) = -0.8 * 500;  // coupled along the normals (z)
  const auto run = [&](bool schedule) {
    HapticLoopSettings settings;
    settings.local_model = LocalModelKind::p;
    settings.hold = HoldKind::zoh;
    settings.schedule_gains = schedule;
    settings.gains = {150, 0};
    settings.safety.max_force_n = 1e9, settings.safety.max_force_rate_n_per_s = 1e12;
    LinearSurfaceEnvironment environment(rest, k0, Eigen::MatrixXd::Zero(6, 6));
    HapticLoop loop(settings, initial_update(environment));
    LockstepSession session(loop, environment);
    std::vector<Eigen::Vector3d> devices{Eigen::Vector3d(0, 0, -0.002), Eigen::Vector3d(0.02, 0, -0.002)};
    // The force's range over the last five frames: zero once settled. Unstable, the loop cannot
    // grow without bound (the contacts are unilateral: they lose contact and come back), so it
    // shows as a sustained oscillation.
    double low = 1e300, high = -1e300, mean = 0;
    for (int j = 0; j < 80; ++j)
      for (int i = 0; i < 50; ++i) {
        const auto& out = session.tick(devices);
        if (j >= 75) low = std::min(low, out[0].normal_force), high = std::max(high, out[0].normal_force), mean += out[0].normal_force / 250;
      }
    return std::make_tuple(high - low, mean, loop.gains().proportional);
  };
  // The closed form says why: P-ZOH with pole -Kh / k on the soft mode k = 100 N/m.
  const auto [fixed_range, fixed_mean, fixed_kh] = run(false);
  EXPECT_EQ(fixed_kh, 150);
  EXPECT_GT(fixed_range, 0.1) << fixed_mean;
  const auto [scheduled_range, scheduled_mean, scheduled_kh] = run(true);
  EXPECT_LT(scheduled_kh, 100 * 0.7);  // below the soft mode's limit with the margin
  EXPECT_GT(scheduled_mean, 0.05);
  EXPECT_LT(scheduled_range, 1e-6 * scheduled_mean);
}

// A change of tissue stiffness reaches the gains through the next update and is blended in over
// blend_ticks ticks, in equal steps: no gain jump.
TEST(HapticLoop, GainChangesAreBlendedOverTicks) {
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi;
  settings.hold = HoldKind::foh;
  settings.blend_ticks = 25;
  ContactFrame rest;
  auto environment = LinearSurfaceEnvironment::isotropic({rest}, 400, 0);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0, 0, -0.002)};
  for (int k = 0; k < 50 * 5; ++k) session.tick(device);
  const double before = loop.gains().proportional;
  environment.set_stiffness(Eigen::MatrixXd::Identity(3, 3) * 1200);
  std::vector<double> kh;
  for (int k = 0; k < 50 * 4; ++k) {
    session.tick(device);
    kh.push_back(loop.gains().proportional);
  }
  const double after = kh.back();
  EXPECT_NEAR(after / before, 3.0, 0.15);  // gains scale with the stiffness (PI: about Kh ~ K0)
  double largest_step = 0;
  for (size_t k = 1; k < kh.size(); ++k) largest_step = std::max(largest_step, std::abs(kh[k] - kh[k - 1]));
  EXPECT_NEAR(largest_step, std::abs(after - before) / 25, 1e-9 * after);
}

// Real time: an answer that misses its frame. The loop counts it, holds the newest surface (FOH
// does not start over from the previous one) and pauses the integrator, so a device held still
// feels a constant force until the answer comes, instead of one that winds up by I e every tick.
TEST(HapticLoop, ALateAnswerHoldsTheNewestSurfaceAndPausesTheIntegrator) {
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi;
  settings.hold = HoldKind::foh;
  settings.schedule_gains = false;
  settings.gains = {300, 4};
  ContactFrame rest;
  auto environment = LinearSurfaceEnvironment::isotropic({rest}, 400, 0);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  const int n = settings.ratio;
  const std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0, 0, -0.002)};
  for (int k = 0; k < 5 * n; ++k) session.tick(device);  // frames 0-4 answered on time
  loop.tick(device);                                      // frame 5 starts; its answer is withheld
  for (int k = 1; k < n; ++k) loop.tick(device);
  EXPECT_EQ(loop.late_answers(), 0);
  std::vector<double> late_forces;
  for (int k = 0; k < n; ++k) {  // frame 6: no answer at its start
    const auto& out = loop.tick(device);
    late_forces.push_back(out[0].normal_force);
    EXPECT_DOUBLE_EQ(out[0].penetration, locate(loop.newest().update.frames[0], device[0]).penetration) << k;
  }
  EXPECT_EQ(loop.late_answers(), 1);
  EXPECT_EQ(loop.first_late_tick(), 6L * n);
  EXPECT_GT(late_forces.front(), 0);
  for (double f : late_forces) EXPECT_EQ(f, late_forces.front());
  session.answer();  // frame 5's answer, one frame late: taken up at frame 7's start
  const double at_start = loop.tick(device)[0].normal_force;
  const double next = loop.tick(device)[0].normal_force;
  EXPECT_NE(next, at_start);  // integrating again
  EXPECT_EQ(loop.late_answers(), 1);
}

// An environment whose frames fail from a given frame on, as the FEM's do past what it can solve:
// each failed frame hands back the last converged answer (environment.h), status not converged.
class FailingFrom final : public Environment {
 public:
  FailingFrom(Environment& inner, long first_failure) : inner_(inner), first_failure_(first_failure) {}
  int contacts() const override { return inner_.contacts(); }
  void initial(EnvironmentUpdate& out) override { inner_.initial(out), last_good_ = out; }
  void solve(const std::vector<ContactSample>& samples, long frame, EnvironmentUpdate& out) override {
    if (frame < first_failure_) {
      inner_.solve(samples, frame, out);
      last_good_ = out;
      return;
    }
    out = last_good_;
    out.frame = frame;
    out.status.converged = false;
    out.status.message = "failed on purpose";
  }

 private:
  Environment& inner_;
  long first_failure_;
  EnvironmentUpdate last_good_;
};

// A press that goes on deepening while the frames fail: the loop holds the last converged surface,
// and the Smith predictor carries the press on from it at the condensed compliance. On a linear
// tissue with W exact that prediction is the tissue's own surface, x_held + W (F - F_ref), so the
// force is the one rendered when every frame converges, tick for tick to round-off, and settles
// at k times the depth. (Each failed frame's forces taken as the reference instead wound the force
// up to the clamp: 3.8 N for 1 N.)
TEST(HapticLoop, FailedFramesKeepTheForceOnTheLastConvergedSurface) {
  const double k = 200;  // N/m
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi_smith;
  settings.hold = HoldKind::zoh;
  ContactFrame rest;
  const auto press = [&](long first_failure) {
    auto tissue = LinearSurfaceEnvironment::isotropic({rest}, k, 0);
    FailingFrom environment(tissue, first_failure);
    HapticLoop loop(settings, initial_update(environment));
    LockstepSession session(loop, environment);
    std::vector<double> force, depth;
    std::vector<Eigen::Vector3d> device(1);
    const int ticks = static_cast<int>(2.0 / settings.period_s);  // 2 s: 5 mm down in 1 s, then held
    for (int t = 0; t < ticks; ++t) {
      const double d = 0.005 * std::min(1.0, t * settings.period_s);
      device[0] = Eigen::Vector3d(0, 0, -d);
      force.push_back(session.tick(device)[0].normal_force);
      depth.push_back(d);
    }
    return std::make_pair(force, depth);
  };
  const auto [converging, depth] = press(1L << 40);
  const auto [failing, unused] = press(10);  // from 0.5 s on (2.5 mm deep, 0.5 N), every frame fails
  double apart = 0;
  for (std::size_t t = 0; t < failing.size(); ++t) apart = std::max(apart, std::abs(failing[t] - converging[t]));
  EXPECT_LT(apart, 1e-9);
  EXPECT_NEAR(failing.back(), k * depth.back(), 1e-6);
}

TEST(HapticLoop, ForcesSentAreAlwaysFiniteAndClamped) {
  HapticLoopSettings settings;
  settings.local_model = LocalModelKind::pi;
  settings.schedule_gains = false;
  settings.gains = {5000, 50};  // far outside the stability region: the loop diverges
  settings.safety.max_force_n = 3.0;
  ContactFrame rest;
  auto environment = LinearSurfaceEnvironment::isotropic({rest}, 400, 0);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0, 0, -0.003)};
  for (int k = 0; k < 50 * 200; ++k) {
    const auto& out = session.tick(device);
    ASSERT_TRUE(out[0].force.allFinite());
    ASSERT_LE(out[0].force.norm(), 3.0 + 1e-12);
  }
  EXPECT_GT(loop.safety(0).clamped_ticks(), 0u);
}

}  // namespace
}  // namespace fetouch::haptics

namespace fetouch::haptics {
namespace {

// The hand-over between a producer thread and the tick, stressed: the producer publishes updates
// as fast as it can, each stamped in two places (the frame number and the Smith reference force);
// the tick promotes at every tick (N = 1) and must only ever hold whole updates, in order.
TEST(HapticLoop, HandOverFromAnotherThreadIsWholeAndInOrder) {
  HapticLoopSettings settings;
  settings.ratio = 1;
  settings.schedule_gains = false;
  settings.gains = {0.2, 0};
  EnvironmentUpdate initial;
  initial.frames.resize(1);
  initial.frames[0].point = Eigen::Vector3d::Zero();
  initial.frames[0].normal = Eigen::Vector3d::UnitZ();
  initial.compliance = Eigen::Matrix3d::Identity() * 1e-3;
  initial.frame = 0;
  HapticLoop loop(settings, initial);
  std::atomic<bool> stop{false};
  std::atomic<long> published{0};
  std::thread producer([&] {
    for (long n = 1; !stop.load(); ++n) {
      FrameSlot& slot = loop.pending_slot();
      slot.update.frame = n;
      slot.normal_force(0) = static_cast<double>(n);
      loop.prepare(slot);
      loop.publish();
      published = n;
    }
  });
  const std::vector<Eigen::Vector3d> device{Eigen::Vector3d(0, 0, 0.001)};
  long last = 0, torn = 0, backwards = 0, changes = 0;
  // Until 2000 different updates were held, or 60 s. On a busy machine (ctest -j2 beside real-time
  // sessions) both threads may share one core: the tick yields every 1000 ticks so that the
  // producer gets its turns (the tick itself never yields; this loop is the test's).
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (long k = 0; changes < 2000 && (k % 4096 != 0 || std::chrono::steady_clock::now() < give_up); ++k) {
    if (k % 1000 == 999) std::this_thread::yield();
    loop.tick(device);
    const FrameSlot& held = loop.newest();
    if (held.update.frame != static_cast<long>(held.normal_force(0)) && held.update.frame != 0) ++torn;
    if (held.update.frame < last) ++backwards;
    if (held.update.frame != last) ++changes;
    last = held.update.frame;
  }
  stop = true;
  producer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_GE(changes, 2000) << "the producer published " << published.load();
}

}  // namespace
}  // namespace fetouch::haptics
