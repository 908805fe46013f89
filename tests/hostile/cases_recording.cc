// Recordings: `fetouch replay SCENE --trajectory FILE.h5` on HDF5 files that are not the documented
// layout (docs/replay.md), written here with the HDF5 C API.
#include <hdf5.h>

#include <cmath>
#include <string>
#include <vector>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

struct Dataset {
  std::string group, name;
  std::vector<hsize_t> dims;
  std::vector<double> values;  // as many as the dims hold, unless `unlimited`
  bool text = false;           // a string dataset instead of numbers
  bool unlimited = false;      // chunked, the extent `dims` declared but never written
};

// A recording of one probe, `rows` samples at 1 kHz of the block poke's first `rows` milliseconds.
std::vector<Dataset> recording(hsize_t rows = 300) {
  std::vector<double> time(rows), position(3 * rows), zeros3(3 * rows, 0.0), zeros(rows, 0.0);
  for (hsize_t r = 0; r < rows; ++r) {
    time[r] = 1e-3 * double(r);
    position[3 * r] = 0.05, position[3 * r + 1] = 0.04, position[3 * r + 2] = 0.06 - 0.01 * time[r];
  }
  const std::string g = "devices/tool";
  return {{g, "time_s", {rows}, time},          {g, "position_m", {rows, 3}, position},
          {g, "velocity_m_per_s", {rows, 3}, zeros3}, {g, "force_n", {rows, 3}, zeros3},
          {g, "proxy_m", {rows, 3}, position},   {g, "penetration_m", {rows}, zeros},
          {g, "normal_force_n", {rows}, zeros},  {g, "in_contact", {rows}, zeros}};
}

Dataset& find(std::vector<Dataset>& sets, const std::string& name) {
  for (auto& d : sets)
    if (d.name == name) return d;
  throw std::runtime_error("no dataset " + name);
}

void write_h5(const fs::path& path, const std::vector<Dataset>& sets, bool with_devices_group = true) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("cannot create " + path.string());
  const hid_t link = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(link, 1);
  if (with_devices_group) H5Gclose(H5Gcreate2(file, "devices", link, H5P_DEFAULT, H5P_DEFAULT));
  for (const Dataset& d : sets) {
    const std::string full = d.group + "/" + d.name;
    hid_t space, dataset, properties = H5Pcreate(H5P_DATASET_CREATE);
    if (d.unlimited) {
      std::vector<hsize_t> max(d.dims.size(), H5S_UNLIMITED), chunk(d.dims.size(), 1);
      space = H5Screate_simple(static_cast<int>(d.dims.size()), d.dims.data(), max.data());
      H5Pset_chunk(properties, static_cast<int>(chunk.size()), chunk.data());
    } else {
      space = H5Screate_simple(static_cast<int>(d.dims.size()), d.dims.data(), nullptr);
    }
    if (d.text) {
      const hid_t type = H5Tcopy(H5T_C_S1);
      H5Tset_size(type, 8);
      dataset = H5Dcreate2(file, full.c_str(), type, space, link, properties, H5P_DEFAULT);
      std::string fill;
      for (double v : d.values) fill += std::to_string(v).substr(0, 7) + '\0';
      H5Dwrite(dataset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, fill.data());
      H5Tclose(type);
    } else {
      dataset = H5Dcreate2(file, full.c_str(), H5T_NATIVE_DOUBLE, space, link, properties, H5P_DEFAULT);
      if (!d.unlimited && !d.values.empty()) H5Dwrite(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values.data());
    }
    H5Dclose(dataset);
    H5Sclose(space);
    H5Pclose(properties);
  }
  H5Pclose(link);
  H5Fclose(file);
}

Invocation replay(const fs::path& dir, const std::string& file, int exit_code = 2) {
  write_block_scene(dir);
  return {{"replay", "scene.yaml", "--trajectory", file, "--out", "out", "--mesh-every", "0"}, file, exit_code};
}

// A recording changed by `edit`.
Case edited(const std::string& name, const std::string& guards, const std::string& form,
            const std::function<void(std::vector<Dataset>&)>& edit, int exit_code = 2) {
  return {name, "recording", guards, form, [=](const fs::path& dir) {
            auto sets = recording();
            edit(sets);
            write_h5(dir / "take.h5", sets);
            return replay(dir, "take.h5", exit_code);
          }};
}

Case bytes(const std::string& name, const std::string& guards, const std::string& form, const std::function<std::string()>& text) {
  return {name, "recording", guards, form, [=](const fs::path& dir) {
            write_text(dir / "take.h5", text());
            return replay(dir, "take.h5");
          }};
}

}  // namespace

std::vector<Case> recording_cases() {
  std::vector<Case> c;
  c.push_back(edited("ValidRecording", "valid", "wrong shape", [](auto&) {}, 0));
  // Shapes other than the layout's (heap corruption before issue 17).
  c.push_back(edited("TimeWithTwoColumns", "crash", "wrong shape", [](auto& s) {
    auto& t = find(s, "time_s");
    t.dims = {t.dims[0], 2}, t.values.resize(2 * t.values.size());
  }));
  c.push_back(edited("PositionsOfRankThree", "crash", "wrong shape", [](auto& s) {
    auto& p = find(s, "position_m");
    p.dims = {p.dims[0], 3, 2}, p.values.resize(2 * p.values.size());
  }));
  c.push_back(edited("PositionsWithTwoColumns", "crash", "wrong shape", [](auto& s) {
    auto& p = find(s, "position_m");
    p.dims = {p.dims[0], 2}, p.values.resize(2 * p.dims[0]);
  }));
  c.push_back(edited("PositionsAsScalar", "crash", "wrong shape", [](auto& s) {
    auto& p = find(s, "position_m");
    p.dims = {}, p.values = {0.05};
  }));
  c.push_back(edited("MalformedFrames", "crash", "wrong shape", [](auto& s) {
    s.push_back({"frames", "frame", {4, 4}, std::vector<double>(16, 1.0)});
  }));
  c.push_back(edited("FramesWithoutTime", "crash", "wrong shape", [](auto& s) {
    s.push_back({"frames", "frame", {4}, {0, 1, 2, 3}});
  }));
  c.push_back(edited("NoTimeDataset", "unclear", "wrong shape", [](auto& s) { s.erase(s.begin()); }));
  c.push_back(edited("TimeAsText", "unclear", "wrong shape", [](auto& s) { find(s, "time_s").text = true; }));
  c.push_back(edited("ATrillionRowsDeclared", "hang", "huge", [](auto& s) {
    auto& t = find(s, "time_s");
    t.dims = {1'000'000'000'000ull}, t.unlimited = true;
  }));
  c.push_back(edited("ZeroRows", "unclear", "truncated", [](auto& s) {
    for (auto& d : s) d.dims[0] = 0, d.values.clear();
  }));
  c.push_back(edited("OneRow", "unclear", "truncated", [](auto& s) {
    for (auto& d : s) d.values.resize(d.values.size() / d.dims[0]), d.dims[0] = 1;
  }));
  c.push_back(edited("LongDeviceName", "crash", "name", [](auto& s) {
    for (auto& d : s) d.group = "devices/" + std::string(400, 'p');
  }));
  // Values.
  c.push_back(edited("NaNTimes", "nonsense", "non-finite", [](auto& s) { find(s, "time_s").values[100] = NAN; }));
  c.push_back(edited("NaNPositions", "nonsense", "non-finite", [](auto& s) { find(s, "position_m").values[301] = NAN; }));
  c.push_back(edited("InfinitePositions", "nonsense", "non-finite", [](auto& s) { find(s, "position_m").values[30] = -INFINITY; }));
  c.push_back(edited("RepeatedTimes", "nonsense", "wrong shape", [](auto& s) { find(s, "time_s").values[101] = find(s, "time_s").values[100]; }));
  c.push_back(edited("TimesRunningBackwards", "nonsense", "wrong shape", [](auto& s) { find(s, "time_s").values[101] = 0; }));
  c.push_back(edited("PositionsInMillimetres", "nonsense", "absurd", [](auto& s) {
    for (double& v : find(s, "position_m").values) v *= 1000;
  }));
  c.push_back(edited("SpanOf1e5Seconds", "hang", "absurd", [](auto& s) { find(s, "time_s").values.back() = 1e5; }));
  // Not a recording at all.
  c.push_back({"NoDevicesGroup", "recording", "unclear", "wrong shape", [](const fs::path& dir) {
                 write_h5(dir / "take.h5", {{"other", "x", {2}, {1, 2}}}, false);
                 return replay(dir, "take.h5");
               }});
  c.push_back({"NoDevices", "recording", "unclear", "wrong shape", [](const fs::path& dir) {
                 write_h5(dir / "take.h5", {});
                 return replay(dir, "take.h5");
               }});
  c.push_back({"TruncatedFile", "recording", "crash", "truncated", [](const fs::path& dir) {
                 write_h5(dir / "whole.h5", recording());
                 const std::string whole = read_text(dir / "whole.h5");
                 fs::remove(dir / "whole.h5");
                 write_text(dir / "take.h5", whole.substr(0, whole.size() / 2));
                 return replay(dir, "take.h5");
               }});
  c.push_back({"CorruptedSuperblock", "recording", "crash", "malformed", [](const fs::path& dir) {
                 write_h5(dir / "whole.h5", recording());
                 std::string whole = read_text(dir / "whole.h5");
                 fs::remove(dir / "whole.h5");
                 const std::string noise = garbage(256, 77);
                 whole.replace(8, noise.size(), noise);  // past the signature: the superblock and root group
                 write_text(dir / "take.h5", whole);
                 return replay(dir, "take.h5");
               }});
  c.push_back(bytes("Garbage", "unclear", "malformed", [] { return garbage(16384, 8); }));
  c.push_back(bytes("Empty", "unclear", "truncated", [] { return std::string(); }));
  c.push_back(bytes("ACsvNamedH5", "unclear", "malformed", [] { return std::string("t_s,x_m,y_m,z_m\n0,0.05,0.04,0.06\n1,0.05,0.04,0.05\n"); }));
  c.push_back({"SparseFourGigabytes", "recording", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "take.h5", 4ull << 30);
                 return replay(dir, "take.h5");
               }});
  c.push_back({"Fifo", "recording", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "take.h5");
                 return replay(dir, "take.h5");
               }});
  // Outputs over the recording being replayed.
  c.push_back({"OutputOverTheRecording", "recording", "overwrite", "output over input", [](const fs::path& dir) {
                 fs::create_directories(dir / "out");
                 write_h5(dir / "out" / "recording.h5", recording());
                 write_block_scene(dir);
                 return Invocation{{"replay", "scene.yaml", "--trajectory", "out/recording.h5", "--out", "out"}, "recording.h5"};
               }});
  c.push_back({"OutputOverThePartialRecording", "recording", "overwrite", "output over input", [](const fs::path& dir) {
                 fs::create_directories(dir / "out");
                 write_h5(dir / "out" / "recording.partial.h5", recording());
                 write_block_scene(dir);
                 return Invocation{{"replay", "scene.yaml", "--trajectory", "out/recording.partial.h5", "--out", "out"}, "recording.partial.h5"};
               }});
  c.push_back({"OutputOverTheRecordingThroughASymlink", "recording", "overwrite", "output over input", [](const fs::path& dir) {
                 fs::create_directories(dir / "out");
                 write_h5(dir / "out" / "recording.h5", recording());
                 fs::create_directory_symlink("out", dir / "alias");
                 write_block_scene(dir);
                 return Invocation{{"replay", "scene.yaml", "--trajectory", "alias/recording.h5", "--out", "out"}, "recording.h5"};
               }});
  return c;
}

}  // namespace fetouch::testing::hostile
