// Devices without hardware (ARCHITECTURE.md section 2): what moves a probe when no PHANTOM is there.
//   - Trajectory: timed probe positions (a CSV of t, x, y, z in s and m, or a recording), resampled
//     to the haptic rate by linear interpolation, held at its last point after its end.
//   - ReplayDevice: plays a trajectory back, tick by tick, whatever force it is sent.
//   - VirtualOperator: a hand model pulled along the trajectory's point (the target) and pushed by
//     the force the device renders, one of two (HandParameters::model):
//       one_mass: a mass m pulled towards the target by a spring k and a damper b,
//         m x'' = k (x_t - x) + b (v_t - v) + F_device;
//       stylus (Fu & Cavusoglu 2012's stylus grip): the handle (the device's own mass m_d) held
//         by the fingers' grip (k1, b1) to the hand's mass m_h, which the arm (k2, b2) pulls to the
//         target,
//         m_d x_d'' = k1 (x_h - x_d) + b1 (v_h - v_d) + F_device,
//         m_h x_h'' = k1 (x_d - x_h) + b1 (v_d - v_h) + k2 (x_t - x_h) + b2 (v_t - v_h);
//     integrated exactly over each tick for inputs held over the tick (zero-order hold: the state
//     transition exp(A T) and its input matrix, computed once), so the force fed back changes the
//     motion as a real hand's would.
// Both are Devices (haptics/device.h): read() and write() never allocate, lock, throw or wait.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "haptics/device.h"
#include "haptics/lock_free.h"

namespace fetouch::haptics {

struct Trajectory {
  std::vector<double> times_s;                // strictly increasing
  std::vector<Eigen::Vector3d> positions_m;   // one per time

  double duration_s() const { return times_s.empty() ? 0 : times_s.back() - times_s.front(); }
  // The position at time t (linear between samples, held before the first and after the last).
  Eigen::Vector3d at(double t) const;
  // Samples every `period_s` from the first time to the last (inclusive when it falls on a tick).
  std::vector<Eigen::Vector3d> resampled(double period_s) const;
  // The longest stretch [from, to] over which the path stays put (0, 0 if it never does).
  std::pair<double, double> longest_hold() const;
  // Throws std::runtime_error starting with `source` unless every value is finite, the times start
  // at 0 or later and increase by at least kMinStepS, the trajectory lasts at most kMaxDurationS,
  // no point is farther than kMaxReachM from the origin and the probe never moves faster than
  // kMaxSpeedMPerS.
  void check(const std::string& source) const;
  static constexpr double kMaxDurationS = 3600;  // an hour: 3.6 million ticks at 1 kHz
  static constexpr double kMaxReachM = 10;       // a probe 10 m from the scene's origin is a unit error
  static constexpr double kMinStepS = 1e-6;      // samples closer than 1 us: no tracker or device gives them
  static constexpr double kMaxSpeedMPerS = 10;   // a hand moves a probe at under 5 m/s
};

// Reads `t, x, y, z` rows (s, m); a header line of names and lines starting with '#' are skipped.
// Throws std::runtime_error naming the file, the line and the value: not four numbers, a time not
// after the previous one, fewer than two rows, a value not finite, then Trajectory::check. Only a
// regular file is read (a FIFO or a device would block or never end), of at most 512 MB.
Trajectory read_trajectory_csv(const std::filesystem::path& path);

// Writes the same format (with a header), full precision.
void write_trajectory_csv(const Trajectory& trajectory, const std::filesystem::path& path, const std::string& comment = "");

// Scripted probe paths, relative to where the probe meets the surface and the surface's outward
// normal there (m, s). Each starts `approach_m` above the point, reaches the surface after
// approach_s, presses `depth_m` along -normal over press_s, then:
//   - poke: holds for hold_s;
//   - slide: moves by `slide_m` (along the surface) over hold_s, still pressed;
//   - squeeze: the same as a poke, meant with long press and release times (a slow squeeze);
// then releases to the surface over release_s and retreats to the start height over retreat_s.
// Positions between the rows are linear (Trajectory::at).
enum class PathShape { poke, slide, squeeze };
struct PathSettings {
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d slide_m = Eigen::Vector3d::Zero();
  double approach_m = 0.01, depth_m = 0.008;
  double approach_s = 0.5, press_s = 0.5, hold_s = 1.0, release_s = 0.5, retreat_s = 0.5;
};
// Throws std::invalid_argument for a zero normal, a negative length or a non-positive duration.
Trajectory scripted_path(PathShape shape, const PathSettings& settings);

class ReplayDevice final : public Device {
 public:
  ReplayDevice(const Trajectory& trajectory, double period_s);
  DeviceState read() noexcept override;
  Eigen::Vector3d write(const Eigen::Vector3d& force_n) noexcept override { return force_n; }
  bool finished() const noexcept override { return tick_ >= static_cast<long>(points_.size()); }
  long ticks() const noexcept override { return static_cast<long>(points_.size()); }

 private:
  std::vector<Eigen::Vector3d> points_;
  double period_s_;
  long tick_ = 0;
};

enum class HandModelKind { one_mass, stylus };

// one_mass: mass_kg, stiffness and damping are the hand's (the project's default hand, 0.3 kg, 300
// N/m, 8 N s/m). stylus: they are the hand's mass m_h and the grip's k1 and b1 (the stage a grip
// event tightens and a release lets go), and the handle's mass and the arm's k2 and b2 come in;
// stylus_hand() has Fu & Cavusoglu's figures (docs/devices.md).
struct HandParameters {
  double mass_kg = 0.3;
  double stiffness_n_per_m = 300;
  double damping_n_s_per_m = 8;
  HandModelKind model = HandModelKind::one_mass;
  double handle_mass_kg = 0.045;          // stylus: m_d, the device's apparent mass at its tip
  double arm_stiffness_n_per_m = 175;     // stylus: k2
  double arm_damping_n_s_per_m = 11;      // stylus: b2
};

// The stylus grip at the middle of Fu & Cavusoglu's (IEEE TSMC-B 42(6), 2012) identified means:
// m_h 0.21 kg (0.20-0.22), k1 575 N/m (380-770), b1 1.3 N s/m (0.8-1.8), k2 175 N/m (79-272),
// b2 11 N s/m (4.6-18); the handle 45 g (a PHANTOM Omni's apparent tip mass).
HandParameters stylus_hand();
const char* to_string(HandModelKind model);

// The hand over one tick of `period_s` with its grip (one_mass: the hand's spring and damper;
// stylus: k1 and b1) multiplied by `grip`, for the state (x_d, v_d, x_h, v_h) of one axis and the
// inputs (F, x_t, v_t) held over the tick (the device holds its force: zero-order hold): exp(A T)
// and int_0^T exp(A s) ds B, exactly. one_mass: x_h and v_h take no part (their rows are the
// identity and nothing else reads them). The operator device steps with it, and so does the lifting
// of the loop with the hand in it (stability_analysis.h).
void hand_transition(const HandParameters& hand, double grip, double period_s, Eigen::Matrix4d& phi,
                     Eigen::Matrix<double, 4, 3>& gamma);

// What an operator may do that tries the loop (passivity-and-identification.md, docs/devices.md):
//   - release at t: the hand's spring and damper (a stylus: the grip's, k1 and b1) drop to zero in
//     one tick; only the mass (a stylus: the handle's) is left, and nothing pulls it to the target;
//   - grip at t: the spring and damper (a stylus: k1 and b1) are multiplied by `factor`, reached
//     linearly over ramp_s (a grip tightening x3 within 10 ms);
//   - tremor from t: the target moves by amplitude_m sin(2 pi f (time - t)) along `direction`
//     (physiological tremor: 6-12 Hz, 0.05-0.5 mm);
//   - impact at t: the hand's velocity (a stylus: both masses') becomes speed_m_per_s along
//     `direction` (a probe arriving at 200 mm/s).
enum class HandEventKind { release, grip, tremor, impact };
struct HandEvent {
  HandEventKind kind = HandEventKind::release;
  double at_s = 0;
  double factor = 3, ramp_s = 0.01;                    // grip
  double frequency_hz = 10, amplitude_m = 2e-4;        // tremor
  double speed_m_per_s = 0.2;                          // impact
  Eigen::Vector3d direction = -Eigen::Vector3d::UnitZ();  // tremor, impact (normalised on use)
};

class VirtualOperator final : public Device {
 public:
  // Starts at rest on the trajectory's first point. Throws std::invalid_argument for a mass,
  // stiffness or damping that is not positive (damping may be zero), or an event that makes no
  // sense (a negative time, a grip factor not positive, a tremor or impact with a zero direction).
  VirtualOperator(const Trajectory& trajectory, const HandParameters& hand, double period_s,
                  const std::vector<HandEvent>& events = {});
  DeviceState read() noexcept override;
  Eigen::Vector3d write(const Eigen::Vector3d& force_n) noexcept override {
    force_ = force_n;
    return force_n;
  }
  bool finished() const noexcept override { return tick_ >= static_cast<long>(targets_.size()); }
  long ticks() const noexcept override { return static_cast<long>(targets_.size()); }
  const Eigen::Vector3d& velocity() const { return velocity_; }

 private:
  // The hand over one tick for the state (x_d, v_d, x_h, v_h) of one axis and the inputs (F, x_t,
  // v_t) held over it: exp(A T) and int_0^T exp(A s) ds B, with the grip it holds by (one_mass:
  // x_h and v_h take no part).
  struct Grip {
    Eigen::Matrix4d phi;
    Eigen::Matrix<double, 4, 3> gamma;
  };
  std::vector<Eigen::Vector3d> targets_, target_velocities_;
  std::vector<Grip> grips_;             // the hand's grips: [0] as given, then those events make
  std::vector<int> grip_of_tick_;       // per tick, which grip
  std::vector<long> impact_ticks_;      // ticks at which an impact sets the velocity, in order
  std::vector<Eigen::Vector3d> impact_velocities_;
  std::size_t next_impact_ = 0;
  Eigen::Vector3d position_, velocity_, force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_position_, hand_velocity_ = Eigen::Vector3d::Zero();  // stylus: x_h, v_h
  long tick_ = 0;
};

// The hand model of VirtualOperator pulled towards a target that another thread moves (the trainer's
// mouse cursor): the probe lags the cursor by the force it meets over the hand's stiffness, which
// is how a mouse user "feels" the tissue. The target goes through a lock-free triple buffer: one
// writer (set_target), the haptic tick the reader. Goes on until the session is stopped.
class CursorOperator final : public Device {
 public:
  // Starts at rest at `start`; throws std::invalid_argument as VirtualOperator does, and for a
  // stylus hand (the mouse's hand is one mass).
  CursorOperator(const Eigen::Vector3d& start, const HandParameters& hand, double period_s);
  // Any one thread (not the tick's): the cursor's new place.
  void set_target(const Eigen::Vector3d& target) noexcept {
    cursor_.back() = target;
    cursor_.publish();
  }
  DeviceState read() noexcept override;
  Eigen::Vector3d write(const Eigen::Vector3d& force_n) noexcept override {
    force_ = force_n;
    return force_n;
  }
  bool finished() const noexcept override { return false; }
  long ticks() const noexcept override { return -1; }

 private:
  TripleBuffer<Eigen::Vector3d> cursor_;
  Eigen::Vector3d target_, position_, velocity_ = Eigen::Vector3d::Zero(), force_ = Eigen::Vector3d::Zero();
  Eigen::Matrix2d phi_;
  Eigen::Vector2d gamma_;
  double stiffness_;
};

}  // namespace fetouch::haptics
