// A haptic session (ARCHITECTURE.md section 5): devices move, the 1 kHz loop renders, the
// environment answers each frame, and everything is recorded (app/recording.h). Two clocks:
//   - lockstep (run_lockstep): simulated time, one thread; the environment answers each frame at
//     once and its answer is applied exactly one frame later. Bit-for-bit reproducible. The runtime
//     adds no timing of its own: with an analytic environment its forces are exactly those of
//     haptics::LockstepSession driven by the same device points.
//   - real time (run_realtime): a haptic thread ticking on an absolute-deadline clock at the
//     loop's period, a solver thread answering the newest frame's samples (handed over through a
//     lock-free triple buffer; the answer goes back through the loop's own lock-free slots), and an
//     I/O thread draining the ticks from a lock-free ring into the recording and flushing it. A
//     solve that outlasts its frame is an overrun: its answer is applied at the first frame start
//     after it arrives, and the hold simply lasts longer. When every solve finishes within its
//     frame the forces are those of the lockstep clock, bit for bit. When a device owns the servo
//     clock (a PHANTOM: Device::servo_clock), the ticks run in its driver's servo callback instead
//     of on the haptic thread's clock. A stop request (SessionSettings::stop) or a device's fault
//     ramps every force out over 0.2 s and ends the session; the recording is closed intact.
// Each tick reads every device, runs the loop, and writes each device's force; what a device says
// it was sent (Device::write) is what is recorded.
#pragma once

#include <array>
#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/recording.h"
#include "haptics/devices.h"
#include "haptics/environment.h"
#include "haptics/haptic_loop.h"
#include "haptics/lock_free.h"

namespace fetouch::app {

// Live figures of a real-time session for a status line, written by the tick (relaxed atomics: no
// lock, no allocation) and read by anyone.
struct SessionMonitor {
  static constexpr int kMaxDevices = 16;
  std::atomic<long> ticks{0}, late_ticks{0};  // late ticks as TimingSummary::tick_overruns counts them
  std::atomic<int> solver_nice{0};  // TimingSummary::solver_nice, once the solver thread has set it
  std::atomic<double> force_n[kMaxDevices] = {};  // the force each device was last sent (magnitude)
  // Each device's last tick, published every tick through a lock-free triple buffer (one reader).
  struct ProbeTick {
    Eigen::Vector3d position = Eigen::Vector3d::Zero(), proxy = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero();
    double penetration = 0;
    bool in_contact = false;
    // The passivity layer (port energy, J; the share s let through) and the identification (the
    // felt stiffness, 0 while not identified, and the frame's condensed one), for the trainer.
    double port_energy_j = 0, passivity_scale = 1;
    double identified_stiffness_n_per_m = 0, condensed_stiffness_n_per_m = 0;
  };
  haptics::TripleBuffer<std::array<ProbeTick, kMaxDevices>> probes{std::array<ProbeTick, kMaxDevices>{}};
};

struct SessionSettings {
  haptics::HapticLoopSettings loop;
  std::vector<std::string> probes;          // one per device, in order
  std::optional<std::filesystem::path> recording;  // the HDF5 file, if any
  RecordingHeader header;                   // probes, rate and ratio are filled in here
  double flush_period_s = 0.5;              // wall-clock time between flushes of the recording
  long max_ticks = -1;                      // < 0: until every device has finished
  // Called after each frame's answer (outside the tick): its row of the recording.
  std::function<void(const FrameRecord&)> after_frame;
  bool keep_forces = false;                 // the summary keeps every force sent (studies)
  bool progress = false;                    // lockstep: frames done and the expected end on stderr
  // Real time: ask for SCHED_FIFO for the haptic thread and nice kSolverNice for the solver's
  // (app/realtime_cores.h; granted to root or with CAP_SYS_NICE; without it the threads run at
  // normal priority, and the summary says so).
  bool realtime_priority = true;
  // Real time on a machine with 2 or more cores: the haptic thread on the last core alone, the
  // solver and I/O threads (and the threads they start) on the others.
  bool pin_haptic_core = true;
  // Set (by a signal handler, a window) to end the session: in real time the forces then ramp out
  // over 0.2 s (a device's fault, Device::fault, ends it the same way); in lockstep, whose devices
  // are scripted, the take ends at the next tick.
  const std::atomic<bool>* stop = nullptr;
  // While set, no tick runs (simulated time stands still, nothing is recorded, devices are neither
  // read nor written); in real time the schedule resumes afresh. A stop request still ends the
  // session. Ignored when a device's driver owns the servo clock.
  const std::atomic<bool>* pause = nullptr;
  SessionMonitor* monitor = nullptr;  // live figures, each tick (optional)
};

// Real-time figures (zero in lockstep).
struct TimingSummary {
  double period_p50_s = 0, period_p99_s = 0, period_max_s = 0;       // between tick starts
  double lateness_p50_s = 0, lateness_p99_s = 0, lateness_max_s = 0; // tick start after its deadline
  long tick_overruns = 0;     // ticks that ended after the next tick's deadline (on a driver's
                              // clock: ticks that started over 1.5 periods after the last one)
  long frame_overruns = 0;    // frame starts at which the previous frame's answer was not there yet
  long first_late_tick = -1;  // the tick of the first (-1: none)
  // Frames the environment solved otherwise than lockstep would (SolveStatus::differs_from_lockstep:
  // a background factorisation not ready where lockstep takes it up), and the first tick that may
  // differ because of them (-1: none). Before both first ticks the forces are lockstep's, bit for bit.
  long solver_differences = 0;
  long first_solver_difference_tick = -1;
  long skipped_frames = 0;    // frames whose samples a newer frame replaced before the solver took them
  long dropped_samples = 0;   // ticks the recording ring had no room for (lost from the recording)
  bool realtime_priority = false;
  int solver_nice = 0;   // the solver thread's nice value (kSolverNice, -10, where it could be raised)
  int haptic_core = -1;  // the core the haptic thread had to itself (-1: not pinned)
};

// The passivity layer's figures for one device (haptics/passivity.h).
struct PassivitySummary {
  long generation_events = 0;      // times the port's energy went from >= 0 to below zero
  long generating_ticks = 0;       // ticks that ended with the port's energy below zero
  long controller_ticks = 0;       // ticks at which the controller changed the force
  long adjusting_ticks = 0;       // ticks at which the controller acted (s moved; HR's damper pushed)
  double max_controller_force_n = 0;
  double min_energy_j = 0;         // the lowest port energy: the most the loop handed the hand
  double min_scale = 1;            // the lowest share of the local model's force let through
  // The frame-rate energy audit (haptics::FrameEnergy): frames that generated more than the
  // tolerance (1 uJ), and the most one frame generated.
  long generating_frames = 0;
  double max_frame_generation_j = 0;
};

// On-line identification for one device (haptics/identification.h): the identified stiffness the
// hand felt against the stiffness the frames condensed, compared at every frame start.
struct IdentificationSummary {
  long frames_compared = 0;        // frame starts in contact with a valid identification
  long disagreements = 0;          // of those, a relative difference over the bound
  double first_disagreement_s = -1;  // when the first was (-1: none)
  double max_relative_difference = 0;
  double last_relative_difference = 0;
};

struct SessionSummary {
  long ticks = 0, frames = 0;
  double solve_p50_s = 0, solve_p99_s = 0, solve_max_s = 0;  // the environment's solve times
  long newton_failures = 0;
  std::string first_failure;         // lockstep: the first failed frame's time and reason ("" if none)
  double max_force_n = 0;            // the largest force sent to a device
  double min_stability_margin = 1;   // 1 - spectral radius of the chosen gains, over the frames
  long frames_with_unstable_gains = 0;
  std::vector<std::vector<Eigen::Vector3d>> forces;  // per device, per tick (keep_forces)
  std::vector<std::vector<Eigen::Vector3d>> positions;  // per device, per tick (keep_forces)
  TimingSummary timing;
  bool stopped = false;                  // ended by a stop request or a fault, not by its end
  std::string fault;                     // the device fault that ended it (empty: none)
  int fault_device = -1;                 // which device had it
  std::vector<long> recoverable_errors;  // per device: recoverable errors (force errors) seen
  std::vector<PassivitySummary> passivity;  // per device
  std::vector<IdentificationSummary> identification;  // per device
  // The frame whose condensed stiffness was the largest (its largest eigenvalue), and the gains and
  // mode it chose: what the lifting with a hand (haptics/stability_analysis.h) is asked about
  // afterwards. Empty eigenvalues: no frame.
  std::vector<double> stiffest_eigenvalues;
  double stiffest_proportional_gain = 0, stiffest_integral_gain = 0;
  int stiffest_local_model = -1, stiffest_hold = -1;
};

// Runs until the devices finish (or max_ticks). Allocation happens only outside the tick.
SessionSummary run_lockstep(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings);

// The same session on the wall clock, in three threads (see above); returns when the devices have
// finished and the last answer and sample are recorded. after_frame runs in the solver thread. An
// exception in the solver or the recording stops the session and is rethrown here.
SessionSummary run_realtime(haptics::Environment& environment, std::vector<std::unique_ptr<haptics::Device>>& devices,
                            const SessionSettings& settings);

// The p-quantile (0..1) of values by nearest rank (ceil(p n)-th smallest); 0 for none.
double percentile(std::vector<double> values, double p);

// The cores run_realtime leaves the solver's threads: all the process may use but the haptic
// thread's (when it has one of its own).
int realtime_solver_cores(const SessionSettings& settings);

// Puts the calling thread (and the threads it starts from now on) on the core run_realtime gives the
// haptic thread (nothing with fewer than 2 cores): for a window's thread and its software
// renderer's threads. The haptic thread, real-time scheduled (SCHED_FIFO), preempts them at each
// tick and leaves them most of that core, while the solver keeps the others to itself.
void share_haptic_core();

}  // namespace fetouch::app
