// A session's recording: one HDF5 file (ARCHITECTURE.md section 6), written by the I/O thread from
// what the haptic and solver threads hand it, readable again as a replay input.
//
// Layout (every dataset chunked and extendable along its first axis):
//   /                      attributes: program_version, scene_path, scene_text, haptic_rate_hz,
//                          ratio, local_model, hold, contacts
//   /devices/<probe>/      one row per haptic tick:
//       time_s [n]; position_m, velocity_m_per_s, force_n, proxy_m [n x 3];
//       penetration_m, normal_force_n [n]; in_contact [n] (0/1);
//       port_energy_j, passivity_scale [n], controller_force_n [n x 3] (the passivity layer);
//       identified_stiffness_n_per_m, identified_damping_n_s_per_m [n] (on-line identification:
//       0 until the contact has moved enough), condensed_stiffness_n_per_m [n] (the newest frame's
//       (W_n^-1)_cc, what the identification is compared with)
//   /frames/               one row per solver frame:
//       frame [n] (int64); time_s, solve_s, residual, stability_margin [n];
//       newton_iterations [n] (int32); converged [n] (0/1);
//       stiffness_eigenvalues_n_per_m [n x m] (of the condensed normal stiffness W_n^-1);
//       gains [n x 2] (Kh, I per tick);
//       mode [n x 2] (uint8: local model 0 p, 1 pi, 2 smith, 3 pi_smith; hold 0 zoh, 1 foh), which
//       changes within a take when the trainer's switch is accepted (absent in older recordings);
//       energy_frame [n] (int64) and hand_energy_j, tissue_work_j, held_energy_j,
//       generated_energy_j [n x m]: the energy audit of frame energy_frame's ticks
//       (haptics::FrameEnergy; absent in recordings before 2026-11-26's audit)
// The file is written in HDF5's single-writer/multiple-reader mode (SWMR): every flush leaves it
// consistent on disk, so a session killed at any moment loses only what came after the last flush
// (the I/O thread flushes at least once a second), and the file can be read while it is written.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "haptics/devices.h"

namespace fetouch::app {

struct RecordingHeader {
  std::string program_version, scene_path, scene_text, local_model, hold;
  double haptic_rate_hz = 1000;
  int ratio = 50;
  std::vector<std::string> probes;  // one device group each, in this order
};

struct DeviceSample {
  double time_s = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero(), velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), proxy = Eigen::Vector3d::Zero();
  double penetration = 0, normal_force = 0;
  bool in_contact = false;
  // The passivity layer (haptics/passivity.h): the energy that has flowed from the hand into the
  // rendering (J; negative: the loop handed the hand energy), and the share s of the local model's
  // force the layer let through (1: untouched). Recordings before 2026-11-26 read back 0 and 1.
  double port_energy_j = 0, passivity_scale = 1;
  // The controller's force c: what it changed in the force the device can be sent (N; zero when
  // it did nothing). Recordings before 2026-11-27 read back zero.
  Eigen::Vector3d controller_force = Eigen::Vector3d::Zero();
  // On-line identification (haptics/identification.h): the stiffness and damping the hand feels,
  // identified from the device's own signals (0 while not identified: out of contact, or too
  // little motion yet), and the stiffness the newest frame condensed for this contact.
  // Recordings before 2026-11-26 read back 0.
  double identified_stiffness_n_per_m = 0, identified_damping_n_s_per_m = 0, condensed_stiffness_n_per_m = 0;
};

struct FrameRecord {
  long frame = 0;
  double time_s = 0, solve_s = 0, residual = 0, stability_margin = 0;
  int newton_iterations = 0;
  bool converged = true;
  std::vector<double> stiffness_eigenvalues;  // m values
  double proportional_gain = 0, integral_gain = 0;
  // The mode those gains are for (haptics::LocalModelKind and HoldKind as integers, the codes of
  // /frames/mode); -1 where a recording read back has no mode column.
  int local_model = -1, hold = -1;
  // The energy audit (haptics::FrameEnergy) of the ticks of frame `energy_frame`, per contact: the
  // frame itself in lockstep, the one before it in real time (the answer's row is written before
  // its own frame's ticks have run). -1 and empty where there is none.
  long energy_frame = -1;
  std::vector<double> hand_energy_j, tissue_work_j, held_energy_j, generated_energy_j;
};

class RecordingWriter {
 public:
  // Writes DIR/STEM.partial.h5 (replacing an earlier partial file), which commit() renames to
  // `path`: an earlier recording at `path` stays whole until the new one is complete, and a session
  // that fails or is killed leaves what it recorded (flushed) in the partial file. Throws
  // std::runtime_error naming the file if it cannot be written.
  RecordingWriter(const std::filesystem::path& path, const RecordingHeader& header);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  void append(int device, const DeviceSample* samples, std::size_t count);
  void append(const FrameRecord& frame);
  // Everything appended so far reaches the disk, consistently.
  void flush();
  // Flushes, closes and puts the file in place (nothing can be appended after).
  void commit();
  long samples(int device) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct RecordedDevice {
  std::string name;
  std::vector<DeviceSample> samples;
};

struct Recording {
  RecordingHeader header;
  std::vector<RecordedDevice> devices;
  std::vector<FrameRecord> frames;
};

// Reads a recording back (also one still being written, or left by a killed session). Throws
// std::runtime_error naming the file and what is missing.
Recording read_recording(const std::filesystem::path& path);

// A probe's path from `file`: a CSV of t, x, y, z, or a recording (.h5), where the probe is found
// by `probe_name`, else the `index`-th device. Checked as Trajectory::check says; throws
// std::runtime_error naming the file.
haptics::Trajectory read_probe_trajectory(const std::filesystem::path& file, const std::string& probe_name, int index);

}  // namespace fetouch::app
