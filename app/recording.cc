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
    std::unique_ptr<Series> port_energy, passivity_scale, controller_force, identified_stiffness, identified_damping, condensed_stiffness;
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
    d.controller_force = std::make_unique<Series>(g, "controller_force_n", H5T_NATIVE_DOUBLE, 3, r.name);
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
  std::vector<double> time(count), position(3 * count), velocity(3 * count), force(3 * count), proxy(3 * count), control(3 * count),
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
      force[3 * i + k] = s.force[k], proxy[3 * i + k] = s.proxy[k], control[3 * i + k] = s.controller_force[k];
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
  d.controller_force->append(control.data(), count);
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

}  // namespace fetouch::app
