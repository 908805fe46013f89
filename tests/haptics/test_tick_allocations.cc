// The haptic tick never allocates (ARCHITECTURE.md section 5). A counting replacement of the global
// operator new, armed only around tick() calls, proves it for every local model and hold, with
// several contacts, FOH interpolation, gain blending, switches of model and hold and unilateral
// contact changes included. The
// environment's solve and the gain selection run outside the armed window: they are the producer
// side of the hand-over, which may allocate.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "haptics/devices.h"
#include "haptics/haptic_loop.h"
#include "haptics/lock_free.h"
#include "haptics/linear_surface_environment.h"

// The replacements pair malloc with free throughout; GCC cannot see that through the inlined
// delete of a replaced new and warns.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

namespace {
std::atomic<bool> armed{false};
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  if (armed.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace fetouch::haptics {
namespace {

long count_tick_allocations(LocalModelKind kind, HoldKind hold, int contacts) {
  ModeChannel modes;
  HapticLoopSettings settings;
  settings.local_model = kind;
  settings.hold = hold;
  settings.blend_ticks = 20;
  settings.modes = &modes;
  std::vector<ContactFrame> rest(contacts);
  for (int c = 0; c < contacts; ++c) {
    rest[c].point = {0.015 * c, 0.002 * c, 0};
    rest[c].normal = Eigen::Vector3d(0.1 * c, 0, 1).normalized();
    rest[c].curvature = Eigen::Matrix2d::Identity() * 10;
  }
  Eigen::MatrixXd k0 = Eigen::MatrixXd::Identity(3 * contacts, 3 * contacts) * 600;
  for (int c = 0; c + 1 < contacts; ++c) k0(3 * c + 2, 3 * c + 5) = k0(3 * c + 5, 3 * c + 2) = -150;
  LinearSurfaceEnvironment environment(rest, k0, k0 * 0.05);
  HapticLoop loop(settings, initial_update(environment));
  LockstepSession session(loop, environment);
  std::vector<Eigen::Vector3d> devices(contacts);
  long counted = 0;
  for (int k = 0; k < 50 * 30; ++k) {
    for (int c = 0; c < contacts; ++c)  // in and out of contact, at different times per contact
      devices[c] = rest[c].point + Eigen::Vector3d(0.001, 0, 0.001 - 0.004 * std::sin(0.004 * k + c));
    if (k == 50 * 12) environment.set_stiffness(k0 * 2.5);  // new gains to blend in
    if (k % (50 * 3) == 25 && k > 50 * 15) {  // a switch to every other mode in turn, taken up by the tick
      const int next = (k / (50 * 3)) % 8;
      modes.ask(static_cast<LocalModelKind>(next / 2), static_cast<HoldKind>(next % 2));
    }
    allocations = 0;
    armed = true;
    loop.tick(devices);
    armed = false;
    counted += allocations;
    if (loop.decimated()) session.answer();  // the producer side, unarmed
  }
  return counted;
}

TEST(TickAllocations, NoneForAnyModelHoldOrContactCount) {
  // The counter itself must see allocations when armed, or the test could not fail.
  armed = true;
  allocations = 0;
  auto* probe = new std::vector<double>(100);
  armed = false;
  delete probe;
  ASSERT_GE(allocations.load(), 1);

  for (LocalModelKind kind : {LocalModelKind::p, LocalModelKind::pi, LocalModelKind::smith, LocalModelKind::pi_smith})
    for (HoldKind hold : {HoldKind::zoh, HoldKind::foh})
      for (int contacts : {1, 4})
        EXPECT_EQ(count_tick_allocations(kind, hold, contacts), 0)
            << "model " << static_cast<int>(kind) << " hold " << static_cast<int>(hold) << " contacts " << contacts;
}

TEST(TickAllocations, NoneInTheDevicesWithoutHardware) {
  Trajectory path;
  path.times_s = {0, 0.2, 0.4};
  path.positions_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -0.01), Eigen::Vector3d(0.01, 0, -0.01)};
  ReplayDevice replay(path, 1e-3);
  VirtualOperator hand(path, HandParameters{}, 1e-3);
  allocations = 0;
  armed = true;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < 600; ++k) sum += replay.next(Eigen::Vector3d(0, 0, 1)) + hand.next(Eigen::Vector3d(0, 0, 1));
  armed = false;
  EXPECT_EQ(allocations.load(), 0);
  EXPECT_TRUE(sum.allFinite());
}

// What the real-time session's haptic thread does besides the tick: copy the frame's samples into
// the triple buffer and publish them, and push the tick's records into the ring.
TEST(TickAllocations, NoneInTheHandOversToOtherThreads) {
  struct Request {
    long frame = -1;
    std::vector<ContactSample> samples = std::vector<ContactSample>(4);
  };
  TripleBuffer<Request> requests{Request{}};
  SpscRing<ContactSample> ring(4 * 64);
  std::vector<ContactSample> samples(4), popped(4 * 64);
  allocations = 0;
  armed = true;
  long refused = 0;
  for (long k = 0; k < 1000; ++k) {
    samples[k % 4].normal_force = double(k);
    Request& r = requests.back();
    r.frame = k;
    std::copy(samples.begin(), samples.end(), r.samples.begin());
    requests.publish();
    refused += !ring.push(samples.data(), samples.size());
  }
  armed = false;
  EXPECT_EQ(allocations.load(), 0);
  EXPECT_GT(refused, 0);  // the ring filled up (nobody drained it) and refused without waiting
  ASSERT_TRUE(requests.take());
  EXPECT_EQ(requests.front().frame, 999);
  EXPECT_EQ(ring.pop(popped.data(), popped.size()), 4u * 64);
}

}  // namespace
}  // namespace fetouch::haptics
