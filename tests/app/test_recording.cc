// The session recording (app/recording.h): written and read back value for value, read while it is
// being written, and left by a process killed with SIGKILL, which must reopen with every sample up
// to at most one second before the kill (the writer flushes twice a second, as the I/O thread does).
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "app/output_guard.h"
#include "app/recording.h"

namespace fetouch::app {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return fs::temp_directory_path() / ("fetouch_recording_" + std::to_string(::getpid()) + "_" + name + ".h5");
}

RecordingHeader header() {
  RecordingHeader h;
  h.program_version = "fetouch 0.test";
  h.scene_path = "/scenes/two.yaml";
  h.scene_text = "name: two\nprobes: [a, b]\n";
  h.local_model = "pi", h.hold = "foh", h.haptic_rate_hz = 1000, h.ratio = 50;
  h.probes = {"left", "right"};
  return h;
}

DeviceSample sample(int device, long k) {
  DeviceSample s;
  s.time_s = k * 1e-3;
  s.position = Eigen::Vector3d(device, std::sin(0.01 * k), -1e-3 * k);
  s.velocity = Eigen::Vector3d(0, 0.01 * std::cos(0.01 * k), -1);
  s.force = Eigen::Vector3d(0.1 * device, 0, 1e-3 * (k % 97));
  s.proxy = s.position + Eigen::Vector3d(0, 0, 1e-4);
  s.penetration = 1e-5 * (k % 13), s.normal_force = 0.5 * (k % 7), s.in_contact = k % 3 == 0;
  s.port_energy_j = -1e-6 * (k % 11), s.passivity_scale = 1.0 / (1 + k % 5);
  s.controller_force = Eigen::Vector3d(0.01 * (k % 3), -0.02 * (k % 7), 0.5 / (1 + k));
  s.identified_stiffness_n_per_m = 40.0 + k % 17, s.identified_damping_n_s_per_m = -0.1 * (k % 3);
  s.condensed_stiffness_n_per_m = 45.0 + device;
  return s;
}

TEST(Recording, RoundTripKeepsEveryValue) {
  const fs::path path = scratch("round");
  {
    RecordingWriter writer(path, header());
    std::vector<DeviceSample> batch(100);
    for (long start = 0; start < 2500; start += 100)
      for (int d = 0; d < 2; ++d) {
        for (long k = 0; k < 100; ++k) batch[k] = sample(d, start + k);
        writer.append(d, batch.data(), batch.size());
      }
    for (long j = 0; j < 50; ++j) {
      FrameRecord f;
      f.frame = j, f.time_s = 0.05 * j, f.solve_s = 0.01 + 1e-4 * j, f.residual = 1e-9 * j, f.stability_margin = 0.3;
      f.newton_iterations = static_cast<int>(j % 4), f.converged = j != 7;
      f.stiffness_eigenvalues = {100.0 + j, 300.0 - j};
      f.proportional_gain = 0.2, f.integral_gain = 1e-3 * j;
      f.local_model = j < 20 ? 3 : 0, f.hold = j < 20 ? 0 : 1;  // pi_smith + zoh, then p + foh
      f.energy_frame = j - 1;
      f.hand_energy_j = {1e-6 * j, -2e-6 * j}, f.tissue_work_j = {3e-7 * j, 0.0};
      f.held_energy_j = {-1e-5 + 1e-7 * j, 4e-6}, f.generated_energy_j = {j % 5 == 0 ? 1e-6 : 0.0, 0.0};
      writer.append(f);
    }
    writer.commit();
  }
  EXPECT_FALSE(fs::exists(partial_path(path)));  // renamed into place
  const Recording r = read_recording(path);
  EXPECT_EQ(r.header.program_version, "fetouch 0.test");
  EXPECT_EQ(r.header.scene_text, header().scene_text);
  EXPECT_EQ(r.header.local_model, "pi");
  EXPECT_EQ(r.header.ratio, 50);
  ASSERT_EQ(r.devices.size(), 2u);
  EXPECT_EQ(r.devices[0].name, "left");
  EXPECT_EQ(r.devices[1].name, "right");
  for (int d = 0; d < 2; ++d) {
    ASSERT_EQ(r.devices[d].samples.size(), 2500u);
    for (long k = 0; k < 2500; k += 37) {
      const DeviceSample e = sample(d, k), &g = r.devices[d].samples[k];
      EXPECT_EQ(g.time_s, e.time_s);
      EXPECT_EQ(g.position, e.position);
      EXPECT_EQ(g.velocity, e.velocity);
      EXPECT_EQ(g.force, e.force);
      EXPECT_EQ(g.proxy, e.proxy);
      EXPECT_EQ(g.penetration, e.penetration);
      EXPECT_EQ(g.normal_force, e.normal_force);
      EXPECT_EQ(g.in_contact, e.in_contact);
      EXPECT_EQ(g.port_energy_j, e.port_energy_j);
      EXPECT_EQ(g.passivity_scale, e.passivity_scale);
      EXPECT_EQ(g.controller_force, e.controller_force);
      EXPECT_EQ(g.identified_stiffness_n_per_m, e.identified_stiffness_n_per_m);
      EXPECT_EQ(g.identified_damping_n_s_per_m, e.identified_damping_n_s_per_m);
      EXPECT_EQ(g.condensed_stiffness_n_per_m, e.condensed_stiffness_n_per_m);
    }
  }
  ASSERT_EQ(r.frames.size(), 50u);
  EXPECT_EQ(r.frames[49].frame, 49);
  EXPECT_FALSE(r.frames[7].converged);
  EXPECT_EQ(r.frames[10].stiffness_eigenvalues, (std::vector<double>{110, 290}));
  EXPECT_EQ(r.frames[10].integral_gain, 1e-3 * 10);
  EXPECT_EQ(r.frames[19].local_model, 3);
  EXPECT_EQ(r.frames[12].energy_frame, 11);
  EXPECT_EQ(r.frames[12].hand_energy_j, (std::vector<double>{1e-6 * 12, -2e-6 * 12}));
  EXPECT_EQ(r.frames[12].tissue_work_j, (std::vector<double>{3e-7 * 12, 0.0}));
  EXPECT_EQ(r.frames[12].held_energy_j, (std::vector<double>{-1e-5 + 1e-7 * 12, 4e-6}));
  EXPECT_EQ(r.frames[15].generated_energy_j, (std::vector<double>{1e-6, 0.0}));
  EXPECT_EQ(r.frames[19].hold, 0);
  EXPECT_EQ(r.frames[20].local_model, 0);
  EXPECT_EQ(r.frames[20].hold, 1);
  fs::remove(path);
}

TEST(Recording, ReadableWhileWritten) {
  const fs::path path = scratch("live");
  RecordingWriter writer(path, header());
  std::vector<DeviceSample> batch(300);
  for (long k = 0; k < 300; ++k) batch[k] = sample(0, k);
  writer.append(0, batch.data(), batch.size());
  writer.flush();  // while it is written, the recording is the partial file
  EXPECT_EQ(read_recording(partial_path(path)).devices[0].samples.size(), 300u);
  writer.append(0, batch.data(), batch.size());
  writer.flush();
  EXPECT_EQ(read_recording(partial_path(path)).devices[0].samples.size(), 600u);
  fs::remove(partial_path(path));
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

TEST(Recording, SurvivesSigkillLosingAtMostOneSecond) {
  const fs::path path = scratch("killed");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The writer: 10 samples every 10 ms stamped with the (system-wide) monotonic clock, flushed
    // every half second, until killed.
    RecordingWriter writer(path, header());
    std::vector<DeviceSample> batch(10);
    double last_flush = now_s();
    for (long k = 0;; k += 10) {
      for (int i = 0; i < 10; ++i) batch[i] = sample(0, k + i), batch[i].time_s = now_s();
      writer.append(0, batch.data(), batch.size());
      writer.append(1, batch.data(), batch.size());
      if (now_s() - last_flush >= 0.5) writer.flush(), last_flush = now_s();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(2700));
  const double killed_at = now_s();
  ASSERT_EQ(kill(child, SIGKILL), 0);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_FALSE(fs::exists(path));  // never completed: only the partial file
  const Recording r = read_recording(partial_path(path));
  ASSERT_EQ(r.devices.size(), 2u);
  const auto& samples = r.devices[0].samples;
  ASSERT_GT(samples.size(), 100u);
  std::printf("%zu samples kept; the last %.3f s before the kill\n", samples.size(), killed_at - samples.back().time_s);
  EXPECT_GE(samples.back().time_s, killed_at - 1.0);
  EXPECT_LE(samples.back().time_s, killed_at);
  for (std::size_t i = 1; i < samples.size(); ++i) ASSERT_GE(samples[i].time_s, samples[i - 1].time_s) << i;
  // Rows kept are whole: the k-th row is the k-th sample written.
  for (std::size_t i = 0; i < samples.size(); i += 53) EXPECT_EQ(samples[i].position, sample(0, static_cast<long>(i)).position);
  fs::remove(partial_path(path));
}

TEST(Recording, NotARecordingIsAnError) {
  const fs::path path = scratch("junk");
  { std::ofstream(path) << "not hdf5"; }
  EXPECT_THROW(read_recording(path), std::runtime_error);
  EXPECT_THROW(read_recording(scratch("absent")), std::runtime_error);
  fs::remove(path);
}

// Recordings whose datasets have other shapes than the documented layout corrupted the heap when
// read (the read fills the buffer with the dataset's whole extent; issue 17). Each is refused,
// naming the file and the dataset, before anything is read or allocated for it.
TEST(Recording, DatasetsOfTheWrongShapeAreRefused) {
  const fs::path good = scratch("shapes_good");
  {
    RecordingWriter writer(good, header());
    std::vector<DeviceSample> batch(10);
    for (int d = 0; d < 2; ++d) {
      for (long k = 0; k < 10; ++k) batch[k] = sample(d, k);
      writer.append(d, batch.data(), batch.size());
    }
    FrameRecord f;
    f.stiffness_eigenvalues = {100, 200};
    writer.append(f);
    writer.commit();
  }
  ASSERT_EQ(read_recording(good).devices.at(0).samples.size(), 10u);
  struct Case {
    const char* dataset;
    std::vector<hsize_t> dims;
  };
  const std::vector<Case> cases = {
      {"devices/left/time_s", {10, 2}},            // time with two columns
      {"devices/left/position_m", {10, 3, 2}},     // positions with three dimensions
      {"devices/right/force_n", {10, 4}},          // four components
      {"devices/left/in_contact", {1000000000}},   // a billion rows claimed (nothing stored)
      {"frames/frame", {1, 5}},                    // a malformed frames dataset
      {"frames/gains", {1}},                       // gains without their two columns
      {"frames/mode", {1, 3}},                     // a mode of three columns
  };
  for (const Case& c : cases) {
    const fs::path bad = scratch(std::string("shapes_") + std::to_string(&c - cases.data()));
    fs::copy_file(good, bad, fs::copy_options::overwrite_existing);
    {
      const hid_t file = H5Fopen(bad.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
      ASSERT_GE(file, 0);
      ASSERT_GE(H5Ldelete(file, c.dataset, H5P_DEFAULT), 0) << c.dataset;
      const hid_t space = H5Screate_simple(static_cast<int>(c.dims.size()), c.dims.data(), nullptr);
      const hid_t dataset = H5Dcreate2(file, c.dataset, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      ASSERT_GE(dataset, 0) << c.dataset;
      H5Dclose(dataset), H5Sclose(space), H5Fclose(file);
    }
    try {
      read_recording(bad);
      ADD_FAILURE() << c.dataset << ": accepted";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      const std::string leaf = fs::path(c.dataset).filename().string();
      EXPECT_NE(what.find(bad.string()), std::string::npos) << what;
      EXPECT_NE(what.find("dataset " + leaf + " has the shape"), std::string::npos) << what;
    }
    fs::remove(bad);
  }
  fs::remove(good);
}

}  // namespace
}  // namespace fetouch::app
