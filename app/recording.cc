#include "app/recording.h"

#include "app/output_guard.h"

#include <hdf5.h>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace fetouch::app {

namespace {

constexpr hsize_t kChunkRows = 1024;

// HDF5's own error printing off (the errors thrown here name the file and the step).
void quiet_hdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error(what);
}

hid_t checked(hid_t id, const std::string& what) {
  if (id < 0) throw std::runtime_error(what);
  return id;
}

// One extendable dataset: rows of `columns` values of `type`.
struct Series {
  hid_t dataset = -1, type = -1;
  hsize_t columns = 1, rows = 0;
  int rank = 1;

  Series(hid_t group, const std::string& name, hid_t value_type, hsize_t value_columns, const std::string& file)
      : type(value_type), columns(value_columns), rank(value_columns > 1 ? 2 : 1) {
    const hsize_t dims[2] = {0, columns}, max[2] = {H5S_UNLIMITED, columns}, chunk[2] = {kChunkRows, columns};
    const hid_t space = checked(H5Screate_simple(rank, dims, max), file + ": cannot describe " + name);
    const hid_t properties = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(properties, rank, chunk);
    dataset = H5Dcreate2(group, name.c_str(), type, space, H5P_DEFAULT, properties, H5P_DEFAULT);
    H5Pclose(properties);
    H5Sclose(space);
    checked(dataset, file + ": cannot create the dataset " + name);
  }
  Series(const Series&) = delete;
  Series& operator=(const Series&) = delete;
  ~Series() {
    if (dataset >= 0) H5Dclose(dataset);
  }

  void append(const void* data, hsize_t n) {
    if (n == 0) return;
    const hsize_t size[2] = {rows + n, columns};
    check(H5Dset_extent(dataset, size), "recording: cannot extend a dataset");
    const hid_t space = H5Dget_space(dataset);
    const hsize_t start[2] = {rows, 0}, count[2] = {n, columns};
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
    const hid_t memory = H5Screate_simple(rank, count, nullptr);
    const herr_t status = H5Dwrite(dataset, type, memory, space, H5P_DEFAULT, data);
    H5Sclose(memory);
    H5Sclose(space);
    check(status, "recording: cannot write a dataset");
    rows += n;
  }
};

void write_attribute(hid_t object, const std::string& name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size() + 1);
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attribute = H5Acreate2(object, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status = attribute < 0 ? -1 : H5Awrite(attribute, type, value.c_str());
  if (attribute >= 0) H5Aclose(attribute);
  H5Sclose(space);
  H5Tclose(type);
  check(status, "recording: cannot write the attribute " + name);
}

void write_attribute(hid_t object, const std::string& name, double value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attribute = H5Acreate2(object, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t status = attribute < 0 ? -1 : H5Awrite(attribute, H5T_NATIVE_DOUBLE, &value);
  if (attribute >= 0) H5Aclose(attribute);
  H5Sclose(space);
  check(status, "recording: cannot write the attribute " + name);
}

hid_t latest_format() {
  const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_libver_bounds(access, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);  // SWMR needs it
  return access;
}

}  // namespace

struct RecordingWriter::Impl {
  std::string name;         // the partial file written to
  std::filesystem::path to;  // where commit() puts it
  hid_t file = -1;
  struct DeviceSeries {
    std::unique_ptr<Series> time, position, velocity, force, proxy, penetration, normal_force, in_contact;
    std::unique_ptr<Series> port_energy, passivity_scale, identified_stiffness, identified_damping, condensed_stiffness;
  };
  std::vector<DeviceSeries> devices;
  std::unique_ptr<Series> frame, time, solve, residual, margin, iterations, converged, eigenvalues, gains, mode;
  std::unique_ptr<Series> energy_frame, hand_energy, tissue_work, held_energy, generated_energy;
  int contacts = 0;

  ~Impl() {
    devices.clear();
    frame.reset(), time.reset(), solve.reset(), residual.reset(), margin.reset(), iterations.reset();
    converged.reset(), eigenvalues.reset(), gains.reset(), mode.reset();
    energy_frame.reset(), hand_energy.reset(), tissue_work.reset(), held_energy.reset(), generated_energy.reset();
    if (file >= 0) H5Fclose(file);
  }
};

RecordingWriter::RecordingWriter(const std::filesystem::path& path, const RecordingHeader& header)
    : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  Impl& r = *impl_;
  r.to = path;
  r.name = partial_path(path).string();
  r.contacts = static_cast<int>(header.probes.size());
  const hid_t access = latest_format();
  r.file = H5Fcreate(r.name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access);
  H5Pclose(access);
  checked(r.file, r.name + ": cannot be created");
  write_attribute(r.file, "program_version", header.program_version);
  write_attribute(r.file, "scene_path", header.scene_path);
  write_attribute(r.file, "scene_text", header.scene_text);
  write_attribute(r.file, "local_model", header.local_model);
  write_attribute(r.file, "hold", header.hold);
  write_attribute(r.file, "haptic_rate_hz", header.haptic_rate_hz);
  write_attribute(r.file, "ratio", header.ratio);
  write_attribute(r.file, "contacts", r.contacts);
  // The probes' groups are listed back in the order they were created.
  const hid_t ordered = H5Pcreate(H5P_GROUP_CREATE);
  H5Pset_link_creation_order(ordered, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  const hid_t devices = H5Gcreate2(r.file, "devices", H5P_DEFAULT, ordered, H5P_DEFAULT);
  H5Pclose(ordered);
  checked(devices, r.name + ": cannot create /devices");
  for (const std::string& probe : header.probes) {
    const hid_t g = checked(H5Gcreate2(devices, probe.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                            r.name + ": cannot create /devices/" + probe);
    Impl::DeviceSeries d;
    d.time = std::make_unique<Series>(g, "time_s", H5T_NATIVE_DOUBLE, 1, r.name);
    d.position = std::make_unique<Series>(g, "position_m", H5T_NATIVE_DOUBLE, 3, r.name);
    d.velocity = std::make_unique<Series>(g, "velocity_m_per_s", H5T_NATIVE_DOUBLE, 3, r.name);
    d.force = std::make_unique<Series>(g, "force_n", H5T_NATIVE_DOUBLE, 3, r.name);
    d.proxy = std::make_unique<Series>(g, "proxy_m", H5T_NATIVE_DOUBLE, 3, r.name);
    d.penetration = std::make_unique<Series>(g, "penetration_m", H5T_NATIVE_DOUBLE, 1, r.name);
    d.normal_force = std::make_unique<Series>(g, "normal_force_n", H5T_NATIVE_DOUBLE, 1, r.name);
    d.in_contact = std::make_unique<Series>(g, "in_contact", H5T_NATIVE_UINT8, 1, r.name);
    d.port_energy = std::make_unique<Series>(g, "port_energy_j", H5T_NATIVE_DOUBLE, 1, r.name);
    d.passivity_scale = std::make_unique<Series>(g, "passivity_scale", H5T_NATIVE_DOUBLE, 1, r.name);
    d.identified_stiffness = std::make_unique<Series>(g, "identified_stiffness_n_per_m", H5T_NATIVE_DOUBLE, 1, r.name);
    d.identified_damping = std::make_unique<Series>(g, "identified_damping_n_s_per_m", H5T_NATIVE_DOUBLE, 1, r.name);
    d.condensed_stiffness = std::make_unique<Series>(g, "condensed_stiffness_n_per_m", H5T_NATIVE_DOUBLE, 1, r.name);
    r.devices.push_back(std::move(d));
    H5Gclose(g);
  }
  H5Gclose(devices);
  const hid_t frames = checked(H5Gcreate2(r.file, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), r.name + ": cannot create /frames");
  r.frame = std::make_unique<Series>(frames, "frame", H5T_NATIVE_INT64, 1, r.name);
  r.time = std::make_unique<Series>(frames, "time_s", H5T_NATIVE_DOUBLE, 1, r.name);
  r.solve = std::make_unique<Series>(frames, "solve_s", H5T_NATIVE_DOUBLE, 1, r.name);
  r.residual = std::make_unique<Series>(frames, "residual", H5T_NATIVE_DOUBLE, 1, r.name);
  r.margin = std::make_unique<Series>(frames, "stability_margin", H5T_NATIVE_DOUBLE, 1, r.name);
  r.iterations = std::make_unique<Series>(frames, "newton_iterations", H5T_NATIVE_INT32, 1, r.name);
  r.converged = std::make_unique<Series>(frames, "converged", H5T_NATIVE_UINT8, 1, r.name);
  r.eigenvalues = std::make_unique<Series>(frames, "stiffness_eigenvalues_n_per_m", H5T_NATIVE_DOUBLE,
                                           static_cast<hsize_t>(std::max(1, r.contacts)), r.name);
  r.gains = std::make_unique<Series>(frames, "gains", H5T_NATIVE_DOUBLE, 2, r.name);
  write_attribute(r.gains->dataset, "columns", "proportional (Kh), integral (I per tick)");
  r.mode = std::make_unique<Series>(frames, "mode", H5T_NATIVE_UINT8, 2, r.name);
  write_attribute(r.mode->dataset, "columns", "local model (0 p, 1 pi, 2 smith, 3 pi_smith), hold (0 zoh, 1 foh)");
  const hsize_t per_contact = static_cast<hsize_t>(std::max(1, r.contacts));
  r.energy_frame = std::make_unique<Series>(frames, "energy_frame", H5T_NATIVE_INT64, 1, r.name);
  r.hand_energy = std::make_unique<Series>(frames, "hand_energy_j", H5T_NATIVE_DOUBLE, per_contact, r.name);
  r.tissue_work = std::make_unique<Series>(frames, "tissue_work_j", H5T_NATIVE_DOUBLE, per_contact, r.name);
  r.held_energy = std::make_unique<Series>(frames, "held_energy_j", H5T_NATIVE_DOUBLE, per_contact, r.name);
  r.generated_energy = std::make_unique<Series>(frames, "generated_energy_j", H5T_NATIVE_DOUBLE, per_contact, r.name);
  H5Gclose(frames);
  // From here on the file stays consistent on disk at every flush.
  check(H5Fstart_swmr_write(r.file), r.name + ": cannot start single-writer/multiple-reader mode");
}

RecordingWriter::~RecordingWriter() {
  try {
    flush();
  } catch (...) {
  }
}

void RecordingWriter::append(int device, const DeviceSample* samples, std::size_t count) {
  Impl::DeviceSeries& d = impl_->devices.at(static_cast<std::size_t>(device));
  std::vector<double> time(count), position(3 * count), velocity(3 * count), force(3 * count), proxy(3 * count),
      penetration(count), normal(count), energy(count), scale(count), identified(count), damping(count), condensed(count);
  std::vector<std::uint8_t> contact(count);
  for (std::size_t i = 0; i < count; ++i) {
    const DeviceSample& s = samples[i];
    time[i] = s.time_s, penetration[i] = s.penetration, normal[i] = s.normal_force, contact[i] = s.in_contact;
    energy[i] = s.port_energy_j, scale[i] = s.passivity_scale;
    identified[i] = s.identified_stiffness_n_per_m, damping[i] = s.identified_damping_n_s_per_m;
    condensed[i] = s.condensed_stiffness_n_per_m;
    for (int k = 0; k < 3; ++k) {
      position[3 * i + k] = s.position[k], velocity[3 * i + k] = s.velocity[k];
      force[3 * i + k] = s.force[k], proxy[3 * i + k] = s.proxy[k];
    }
  }
  d.time->append(time.data(), count);
  d.position->append(position.data(), count);
  d.velocity->append(velocity.data(), count);
  d.force->append(force.data(), count);
  d.proxy->append(proxy.data(), count);
  d.penetration->append(penetration.data(), count);
  d.normal_force->append(normal.data(), count);
  d.in_contact->append(contact.data(), count);
  d.port_energy->append(energy.data(), count);
  d.passivity_scale->append(scale.data(), count);
  d.identified_stiffness->append(identified.data(), count);
  d.identified_damping->append(damping.data(), count);
  d.condensed_stiffness->append(condensed.data(), count);
}

void RecordingWriter::append(const FrameRecord& f) {
  Impl& r = *impl_;
  const std::int64_t frame = f.frame;
  const std::int32_t iterations = f.newton_iterations;
  const std::uint8_t converged = f.converged;
  std::vector<double> eigenvalues(static_cast<std::size_t>(std::max(1, r.contacts)), 0.0);
  for (std::size_t i = 0; i < eigenvalues.size() && i < f.stiffness_eigenvalues.size(); ++i) eigenvalues[i] = f.stiffness_eigenvalues[i];
  const double gains[2] = {f.proportional_gain, f.integral_gain};
  r.frame->append(&frame, 1);
  r.time->append(&f.time_s, 1);
  r.solve->append(&f.solve_s, 1);
  r.residual->append(&f.residual, 1);
  r.margin->append(&f.stability_margin, 1);
  r.iterations->append(&iterations, 1);
  r.converged->append(&converged, 1);
  r.eigenvalues->append(eigenvalues.data(), 1);
  r.gains->append(gains, 1);
  const std::uint8_t mode[2] = {static_cast<std::uint8_t>(std::max(0, f.local_model)), static_cast<std::uint8_t>(std::max(0, f.hold))};
  r.mode->append(mode, 1);
  const std::int64_t energy_frame = f.energy_frame;
  r.energy_frame->append(&energy_frame, 1);
  const auto per_contact = [&](const std::vector<double>& values) {
    std::vector<double> row(static_cast<std::size_t>(std::max(1, r.contacts)), 0.0);
    for (std::size_t i = 0; i < row.size() && i < values.size(); ++i) row[i] = values[i];
    return row;
  };
  r.hand_energy->append(per_contact(f.hand_energy_j).data(), 1);
  r.tissue_work->append(per_contact(f.tissue_work_j).data(), 1);
  r.held_energy->append(per_contact(f.held_energy_j).data(), 1);
  r.generated_energy->append(per_contact(f.generated_energy_j).data(), 1);
}

void RecordingWriter::flush() {
  if (impl_->file < 0) return;
  check(H5Fflush(impl_->file, H5F_SCOPE_GLOBAL), impl_->name + ": cannot be flushed");
}

void RecordingWriter::commit() {
  Impl& r = *impl_;
  if (r.file < 0) return;
  flush();
  const std::string name = r.name;
  r.devices.clear();  // every dataset closed before the file
  r.frame.reset(), r.time.reset(), r.solve.reset(), r.residual.reset(), r.margin.reset(), r.iterations.reset();
  r.converged.reset(), r.eigenvalues.reset(), r.gains.reset(), r.mode.reset();
  const herr_t closed = H5Fclose(r.file);
  r.file = -1;
  check(closed, name + ": cannot be closed");
  std::error_code error;
  std::filesystem::rename(name, r.to, error);
  if (error) throw std::runtime_error(name + ": cannot be renamed to " + r.to.string() + " (" + error.message() + ")");
}

long RecordingWriter::samples(int device) const {
  return static_cast<long>(impl_->devices.at(static_cast<std::size_t>(device)).time->rows);
}

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
