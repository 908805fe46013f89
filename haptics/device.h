// The one device interface (ARCHITECTURE.md section 2), as CHAI3D's device layer has it: every
// family (replay, virtual operator, PHANTOM) is opened by its constructor, read and written once a
// tick, and closed by its destructor. A tick is read() (pose, velocity, buttons), the local model,
// then write() (the force). A device whose driver owns the servo clock (a PHANTOM: the vendor's
// scheduler thread) says so through servo_clock(), and the session's tick then runs in its callback.
//
// read(), write() and fault() are called from the haptic thread (or the driver's servo thread):
// they never allocate, lock, throw or wait. Positions and forces are in the scene frame, SI units.
#pragma once

#include <Eigen/Core>

#include <cstdint>

namespace fetouch::haptics {

struct DeviceState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_m_per_s = Eigen::Vector3d::Zero();
  std::uint32_t buttons = 0;  // bit i: button i held
};

// A driver's servo thread, calling the session's tick once per servo period.
class ServoClock {
 public:
  // One tick; returns false when the session is over (the clock then stops calling it).
  using Tick = bool (*)(void* context) noexcept;
  virtual ~ServoClock() = default;
  // Starts calling tick(context) on the driver's thread. Throws std::runtime_error naming the
  // driver's error when it cannot start.
  virtual void start(Tick tick, void* context) = 0;
  // Stops the calls; when it returns, no tick is running and none will.
  virtual void stop() noexcept = 0;
  virtual double period_s() const noexcept = 0;
};

class Device {
 public:
  virtual ~Device() = default;
  // The device at the start of this tick (a replay or a hand model advances by one tick here,
  // under the force written at the last one).
  virtual DeviceState read() noexcept = 0;
  // The force for this tick (N, scene frame, already finite and clamped by the safety layer).
  // Returns the force the device was actually given, in the scene frame: a device may scale it
  // down (a ramp at engage, a clutch, a force error), and the session records what was sent.
  virtual Eigen::Vector3d write(const Eigen::Vector3d& force_n) noexcept = 0;
  // True once the device has nothing more to play (a trajectory's end); never for hardware.
  virtual bool finished() const noexcept = 0;
  // The ticks it lasts; -1 for a device that goes on until the session is stopped.
  virtual long ticks() const noexcept = 0;
  // The driver's servo clock, for a device that has one (nullptr: the session keeps time).
  virtual ServoClock* servo_clock() noexcept { return nullptr; }
  // A fault that ends the session (a device or communication error), or nullptr: a static text.
  virtual const char* fault() const noexcept { return nullptr; }
  // Errors the device recovered from (force errors: the force was off until they cleared).
  virtual long recoverable_errors() const noexcept { return 0; }

  // write() then read(): the point for the next tick given the force rendered at the last one.
  Eigen::Vector3d next(const Eigen::Vector3d& rendered_force) noexcept {
    write(rendered_force);
    return read().position_m;
  }
};

}  // namespace fetouch::haptics
