// Reading a session's recording back (app/recording.h): the datasets' shapes checked against the
// documented layout (docs/replay.md) before anything is read, older recordings' missing columns
// read as their defaults.
#include "app/recording.h"

#include <hdf5.h>

#include <algorithm>
#include <stdexcept>

namespace fetouch::app {

namespace {

// HDF5's own error printing off (the errors thrown here name the file and the step).
void quiet_hdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// A file written in single-writer/multiple-reader mode is opened with the latest format bounds.
hid_t latest_format() {
  const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_libver_bounds(access, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
  return access;
}

}  // namespace

namespace {

// Rows a dataset may have: 10^8 samples are 28 hours at 1 kHz. A file that claims more is refused
// before anything is allocated for it.
constexpr hsize_t kMaxRows = 100'000'000;

// A whole dataset (rows x columns) as doubles, integer values converted. Its shape is checked
// against the documented layout (docs/replay.md) before anything is read: the read fills the
// buffer with the dataset's whole extent, whatever its rank.
std::vector<double> read_all(hid_t group, const std::string& name, hsize_t columns, const std::string& file) {
  const hid_t dataset = H5Dopen2(group, name.c_str(), H5P_DEFAULT);
  if (dataset < 0) throw std::runtime_error(file + ": no dataset " + name);
  H5Drefresh(dataset);  // the newest extent a writer has flushed
  const hid_t space = H5Dget_space(dataset);
  const int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
  hsize_t dims[H5S_MAX_RANK] = {0};
  if (rank >= 0) H5Sget_simple_extent_dims(space, dims, nullptr);
  if (space >= 0) H5Sclose(space);
  const int expected = columns > 1 ? 2 : 1;
  if (rank != expected || (rank == 2 && dims[1] != columns) || dims[0] > kMaxRows) {
    H5Dclose(dataset);
    std::string shape = "(";
    for (int k = 0; k < rank; ++k) shape += (k ? " x " : "") + std::to_string(dims[k]);
    shape += rank < 0 ? "unreadable)" : ")";
    throw std::runtime_error(file + ": dataset " + name + " has the shape " + shape + "; a recording has " +
                             (expected == 1 ? std::string("one value per row") : std::to_string(columns) + " per row") +
                             (dims[0] > kMaxRows ? " and at most 10^8 rows" : "") + " (docs/replay.md)");
  }
  // Numbers of a standard layout: IEEE floats of 4 or 8 bytes, whole integers of 1 to 8 bytes. (A
  // float type of another size or layout sends HDF5 into a slow element-by-element conversion.)
  const hid_t stored = H5Dget_type(dataset);
  const H5T_class_t kind = stored < 0 ? H5T_NO_CLASS : H5Tget_class(stored);
  bool standard = false;
  if (kind == H5T_FLOAT)
    for (const hid_t ieee : {H5T_IEEE_F32LE, H5T_IEEE_F32BE, H5T_IEEE_F64LE, H5T_IEEE_F64BE}) standard = standard || H5Tequal(stored, ieee) > 0;
  if (kind == H5T_INTEGER) {
    const std::size_t bytes = H5Tget_size(stored);
    standard = (bytes == 1 || bytes == 2 || bytes == 4 || bytes == 8) && H5Tget_precision(stored) == 8 * bytes && H5Tget_offset(stored) == 0;
  }
  if (stored >= 0) H5Tclose(stored);
  if (!standard) {
    H5Dclose(dataset);
    throw std::runtime_error(file + ": dataset " + name + " does not hold numbers of a standard type; a recording's datasets are IEEE floats or integers (docs/replay.md)");
  }
  // The rows must be in the file: a few kilobytes declaring 10^8 rows would have HDF5 fill gigabytes
  // with fill values (recordings are not compressed; a 64-fold margin covers any filter).
  std::error_code error;
  const double file_bytes = double(std::filesystem::file_size(file, error));
  if (double(dims[0]) * double(columns) * 8 > 64 * file_bytes + (1 << 20)) {
    H5Dclose(dataset);
    throw std::runtime_error(file + ": dataset " + name + " declares " + std::to_string(dims[0]) +
                             " rows that the file does not hold (" + std::to_string(static_cast<long long>(file_bytes)) + " bytes)");
  }
  std::vector<double> values(static_cast<std::size_t>(dims[0] * columns));
  const herr_t status = values.empty() ? 0 : H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Dclose(dataset);
  if (status < 0) throw std::runtime_error(file + ": cannot read " + name);
  return values;
}

std::string read_text(hid_t object, const std::string& name) {
  const hid_t attribute = H5Aopen(object, name.c_str(), H5P_DEFAULT);
  if (attribute < 0) return {};
  const hid_t type = H5Aget_type(attribute);
  std::string value(H5Tget_size(type), '\0');
  const hid_t memory = H5Tcopy(H5T_C_S1);
  H5Tset_size(memory, value.size());
  H5Aread(attribute, memory, value.data());
  H5Tclose(memory);
  H5Tclose(type);
  H5Aclose(attribute);
  value.resize(value.find('\0') == std::string::npos ? value.size() : value.find('\0'));
  return value;
}

double read_number(hid_t object, const std::string& name) {
  double value = 0;
  const hid_t attribute = H5Aopen(object, name.c_str(), H5P_DEFAULT);
  if (attribute < 0) return 0;
  H5Aread(attribute, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attribute);
  return value;
}

}  // namespace

Recording read_recording(const std::filesystem::path& path) {
  quiet_hdf5();
  const std::string name = path.string();
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw std::runtime_error(name + ": no such file");
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(name + ": not a regular file (a recording is an HDF5 file, not a folder, FIFO or device)");
  const hid_t access = latest_format();
  hid_t file = H5Fopen(name.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, access);
  if (file < 0) file = H5Fopen(name.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  H5Pclose(access);
  if (file < 0) throw std::runtime_error(name + ": not a readable HDF5 recording");
  Recording out;
  try {
    out.header.program_version = read_text(file, "program_version");
    out.header.scene_path = read_text(file, "scene_path");
    out.header.scene_text = read_text(file, "scene_text");
    out.header.local_model = read_text(file, "local_model");
    out.header.hold = read_text(file, "hold");
    out.header.haptic_rate_hz = read_number(file, "haptic_rate_hz");
    out.header.ratio = static_cast<int>(read_number(file, "ratio"));
    const hid_t devices = H5Gopen2(file, "devices", H5P_DEFAULT);
    if (devices < 0) throw std::runtime_error(name + ": no /devices group (not a Fetouch recording)");
    H5G_info_t info;
    H5Gget_info(devices, &info);
    if (info.nlinks == 0) throw std::runtime_error(name + ": /devices holds no device (an empty recording)");
    if (info.nlinks > 64) throw std::runtime_error(name + ": /devices holds " + std::to_string(info.nlinks) + " devices; a recording has at most 64");
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      H5_index_t order = H5_INDEX_CRT_ORDER;
      ssize_t length = H5Lget_name_by_idx(devices, ".", order, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
      if (length < 0) order = H5_INDEX_NAME, length = H5Lget_name_by_idx(devices, ".", order, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
      if (length <= 0 || length > 255)
        throw std::runtime_error(name + ": device " + std::to_string(i) + " in /devices has a name of " + std::to_string(length) +
                                 " characters; names have 1 to 255");
      std::string probe(static_cast<std::size_t>(length) + 1, '\0');
      H5Lget_name_by_idx(devices, ".", order, H5_ITER_INC, i, probe.data(), probe.size(), H5P_DEFAULT);
      probe.resize(static_cast<std::size_t>(length));
      const hid_t g = H5Gopen2(devices, probe.c_str(), H5P_DEFAULT);
      if (g < 0) throw std::runtime_error(name + ": /devices/" + probe + " is not a group of datasets (docs/replay.md)");
      const auto time = read_all(g, "time_s", 1, name);
      const auto position = read_all(g, "position_m", 3, name);
      const auto velocity = read_all(g, "velocity_m_per_s", 3, name);
      const auto force = read_all(g, "force_n", 3, name);
      const auto proxy = read_all(g, "proxy_m", 3, name);
      const auto penetration = read_all(g, "penetration_m", 1, name);
      const auto normal = read_all(g, "normal_force_n", 1, name);
      const auto contact = read_all(g, "in_contact", 1, name);
      const bool has_passivity = H5Lexists(g, "port_energy_j", H5P_DEFAULT) > 0 &&
                                 H5Lexists(g, "passivity_scale", H5P_DEFAULT) > 0;  // since 2026-11-26
      const auto energy = has_passivity ? read_all(g, "port_energy_j", 1, name) : std::vector<double>{};
      const auto scale = has_passivity ? read_all(g, "passivity_scale", 1, name) : std::vector<double>{};
      const bool has_control = H5Lexists(g, "controller_force_n", H5P_DEFAULT) > 0;  // since 2026-11-27
      const auto control = has_control ? read_all(g, "controller_force_n", 3, name) : std::vector<double>{};
      const bool has_identification = H5Lexists(g, "identified_stiffness_n_per_m", H5P_DEFAULT) > 0 &&
                                      H5Lexists(g, "identified_damping_n_s_per_m", H5P_DEFAULT) > 0 &&
                                      H5Lexists(g, "condensed_stiffness_n_per_m", H5P_DEFAULT) > 0;  // since 2026-11-26
      const auto identified = has_identification ? read_all(g, "identified_stiffness_n_per_m", 1, name) : std::vector<double>{};
      const auto damping = has_identification ? read_all(g, "identified_damping_n_s_per_m", 1, name) : std::vector<double>{};
      const auto condensed = has_identification ? read_all(g, "condensed_stiffness_n_per_m", 1, name) : std::vector<double>{};
      H5Gclose(g);
      // Datasets are extended one after the other: a session killed between two keeps the rows
      // every dataset has.
      std::size_t rows = std::min({time.size(), position.size() / 3, velocity.size() / 3, force.size() / 3,
                                   proxy.size() / 3, penetration.size(), normal.size(), contact.size()});
      if (has_passivity) rows = std::min({rows, energy.size(), scale.size()});
      if (has_identification) rows = std::min({rows, identified.size(), damping.size(), condensed.size()});
      if (has_control) rows = std::min(rows, control.size() / 3);
      RecordedDevice d;
      d.name = probe;
      d.samples.resize(rows);
      for (std::size_t r = 0; r < rows; ++r) {
        DeviceSample& s = d.samples[r];
        s.time_s = time[r], s.penetration = penetration[r], s.normal_force = normal[r], s.in_contact = contact[r] != 0;
        if (has_passivity) s.port_energy_j = energy[r], s.passivity_scale = scale[r];
        if (has_identification)
          s.identified_stiffness_n_per_m = identified[r], s.identified_damping_n_s_per_m = damping[r],
          s.condensed_stiffness_n_per_m = condensed[r];
        for (int k = 0; k < 3; ++k) {
          s.position[k] = position[3 * r + k], s.velocity[k] = velocity[3 * r + k];
          s.force[k] = force[3 * r + k], s.proxy[k] = proxy[3 * r + k];
          if (has_control) s.controller_force[k] = control[3 * r + k];
        }
      }
      out.header.probes.push_back(d.name);
      out.devices.push_back(std::move(d));
    }
    H5Gclose(devices);
    const hid_t frames = H5Gopen2(file, "frames", H5P_DEFAULT);
    if (frames >= 0) {
      const auto frame = read_all(frames, "frame", 1, name);
      const auto time = read_all(frames, "time_s", 1, name);
      const auto solve = read_all(frames, "solve_s", 1, name);
      const auto residual = read_all(frames, "residual", 1, name);
      const auto margin = read_all(frames, "stability_margin", 1, name);
      const auto iterations = read_all(frames, "newton_iterations", 1, name);
      const auto converged = read_all(frames, "converged", 1, name);
      const hsize_t contacts = std::max<hsize_t>(1, out.devices.size());
      const auto eigenvalues = read_all(frames, "stiffness_eigenvalues_n_per_m", contacts, name);
      const auto gains = read_all(frames, "gains", 2, name);
      const bool has_mode = H5Lexists(frames, "mode", H5P_DEFAULT) > 0;  // since 2026-11-25
      const auto mode = has_mode ? read_all(frames, "mode", 2, name) : std::vector<double>{};
      const bool has_audit = H5Lexists(frames, "energy_frame", H5P_DEFAULT) > 0;  // since 2026-11-26
      const auto audit = [&](const char* dataset) {
        return has_audit ? read_all(frames, dataset, contacts, name) : std::vector<double>{};
      };
      const auto energy_frame = has_audit ? read_all(frames, "energy_frame", 1, name) : std::vector<double>{};
      const auto hand = audit("hand_energy_j"), tissue = audit("tissue_work_j"), coupling = audit("held_energy_j"),
                 generated = audit("generated_energy_j");
      H5Gclose(frames);
      const std::size_t rows = std::min({frame.size(), time.size(), solve.size(), residual.size(), margin.size(),
                                         iterations.size(), converged.size(), std::size_t(eigenvalues.size() / contacts), gains.size() / 2});
      for (std::size_t r = 0; r < rows; ++r) {
        FrameRecord f;
        f.frame = static_cast<long>(frame[r]), f.time_s = time[r], f.solve_s = solve[r], f.residual = residual[r];
        f.stability_margin = margin[r], f.newton_iterations = static_cast<int>(iterations[r]), f.converged = converged[r] != 0;
        f.stiffness_eigenvalues.assign(eigenvalues.begin() + static_cast<long>(r * contacts),
                                       eigenvalues.begin() + static_cast<long>((r + 1) * contacts));
        f.proportional_gain = gains[2 * r], f.integral_gain = gains[2 * r + 1];
        if (2 * r + 1 < mode.size()) {
          const double model = mode[2 * r], hold = mode[2 * r + 1];
          if (!(model >= 0 && model <= 3 && hold >= 0 && hold <= 1))
            throw std::runtime_error(name + ": /frames/mode row " + std::to_string(r) + " holds (" + std::to_string(model) + ", " +
                                     std::to_string(hold) + "); local models are 0 to 3 and holds 0 or 1 (docs/replay.md)");
          f.local_model = static_cast<int>(model), f.hold = static_cast<int>(hold);
        }
        if (r < energy_frame.size() && (r + 1) * contacts <= std::min({hand.size(), tissue.size(), coupling.size(), generated.size()})) {
          const auto row = [&](const std::vector<double>& v) {
            return std::vector<double>(v.begin() + static_cast<long>(r * contacts), v.begin() + static_cast<long>((r + 1) * contacts));
          };
          f.energy_frame = static_cast<long>(energy_frame[r]);
          f.hand_energy_j = row(hand), f.tissue_work_j = row(tissue), f.held_energy_j = row(coupling);
          f.generated_energy_j = row(generated);
        }
        out.frames.push_back(f);
      }
    }
  } catch (...) {
    H5Fclose(file);
    throw;
  }
  H5Fclose(file);
  return out;
}

haptics::Trajectory read_probe_trajectory(const std::filesystem::path& file, const std::string& probe_name, int index) {
  if (file.extension() != ".h5") return haptics::read_trajectory_csv(file);
  const Recording r = read_recording(file);
  const RecordedDevice* d = nullptr;
  for (const auto& device : r.devices)
    if (device.name == probe_name) d = &device;
  if (!d && index < static_cast<int>(r.devices.size())) d = &r.devices[static_cast<std::size_t>(index)];
  if (!d || d->samples.size() < 2)
    throw std::runtime_error(file.string() + ": no positions for probe " + probe_name + " (at least two samples)");
  haptics::Trajectory t;
  for (const auto& s : d->samples) t.times_s.push_back(s.time_s), t.positions_m.push_back(s.position);
  t.check(file.string() + " (probe " + d->name + ")");
  return t;
}


}  // namespace fetouch::app
