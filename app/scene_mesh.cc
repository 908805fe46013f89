#include "app/scene_mesh.h"

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "app/log.h"
#include "app/recording.h"
#include "config/scene_loader.h"
#include "imaging/phantom.h"
#include "imaging/volume_io.h"
#include "app/mesh_pipeline.h"
#include "meshes/mesh_regions.h"

namespace fetouch::app {

namespace fs = std::filesystem;

namespace {

// The mesher's revision: raised whenever the same volume and options give a different mesh (2: the
// boundary moved out to the segmented volume, regions by their labels' cover; 3: CGAL's restricted
// Delaunay surface filled by HXT first; 4: Gmsh's Delaunay mesher before HXT, so that the same scene
// meshes the same on every machine), so that a mesh cached by an older Fetouch is made again. The
// conforming mesher is a surface of its own in the key, and per-region sizes are added only when given.
constexpr int kMesherRevision = 4;

// What decides the mesh: the mesher's revision, the volume (path, size, modification time) and
// every meshing option.
std::string cache_key(const config::MeshSpec& spec) {
  std::ostringstream key;
  key.precision(17);
  key << "mesher " << kMesherRevision << '|';
  const auto& m = spec.meshing;
  std::error_code ec;
  if (spec.source == config::MeshSource::phantom) {
    key << "phantom|" << spec.phantom.seed << '|' << spec.phantom.spacing_m;
    const auto& o = spec.phantom.fetus_offset_m;
    if (o[0] != 0 || o[1] != 0 || o[2] != 0) key << "|fetus+" << o[0] << ',' << o[1] << ',' << o[2];
    if (const auto& pose = spec.phantom.pose)
      key << "|pose " << config::to_string(pose->lie) << ',' << config::to_string(pose->presentation) << ','
          << config::to_string(pose->back) << ',' << config::to_string(pose->head_side);
    if (spec.phantom.gestational_age_weeks) key << "|weeks " << *spec.phantom.gestational_age_weeks;
  } else if (fs::is_regular_file(spec.path, ec)) {
    key << fs::absolute(spec.path).string() << '|';
    key << fs::file_size(spec.path, ec) << '|' << fs::last_write_time(spec.path, ec).time_since_epoch().count();
  } else {
    key << fs::absolute(spec.path).string() << '|';
    for (const auto& entry : fs::directory_iterator(spec.path, ec))
      key << entry.path().filename().string() << ':' << entry.last_write_time(ec).time_since_epoch().count() << ',';
  }
  key << '|' << m.target_size_m << '|' << m.fetus << '|' << (m.threshold ? *m.threshold : -1.0) << '|'
      << static_cast<int>(m.smoothing) << '|' << m.smoothing_sigma_m << '|' << m.closing_voxels << '|'
      << static_cast<int>(m.surface) << '|';
  // The conforming mesher's own revision (2: Lloyd smoothing and the interface-aware repair), kept
  // apart so that the other paths' cached meshes stay valid.
  if (m.surface == config::MeshSurface::conforming) key << "conforming 2|";
  if (m.regions_from_image) key << "image regions|";
  for (const auto& [name, size] : m.sizes_m) key << name << ':' << size << ',';
  for (int l : m.labels) key << l << ',';
  for (const auto& [name, labels] : m.regions) {
    key << '|' << name << '=';
    for (int l : labels) key << l << ',';
  }
  for (const auto& ball : m.refine_balls)  // one ball spelled as before there were several
    key << '|' << ball.center_m[0] << ',' << ball.center_m[1] << ',' << ball.center_m[2] << ',' << ball.radius_m << ','
        << m.refine_size_m;
  return key.str();
}

void mesh_into(const config::MeshSpec& spec, const fs::path& file) {
  const auto& m = spec.meshing;
  const auto start = std::chrono::steady_clock::now();
  imaging::Volume<float> volume;
  if (spec.source == config::MeshSource::phantom) {
    log::info() << "meshing the scene's phantom (seed " << spec.phantom.seed << "; once, cached as " << file.string() << ")";
    imaging::PhantomSettings p = phantom_settings(spec.phantom);
    p.speckle = false;  // only the labels are meshed
    const imaging::Phantom phantom = imaging::make_phantom(p);
    const auto& l = phantom.labels;
    volume.dimensions = l.dimensions, volume.spacing_mm = l.spacing_mm, volume.origin_mm = l.origin_mm;
    volume.direction = l.direction;
    volume.data.assign(l.data.begin(), l.data.end());
  } else {
    log::info() << "meshing the scene's volume " << spec.path.string() << " (once; cached as " << file.string() << ")";
    volume = imaging::read_volume(spec.path);
  }
  MeshRequest request = mesh_request(m);
  request.settings.progress = [](const std::string& step, double) { log::detail() << "meshing: " << step; };
  meshes::VolumeMesh mesh = mesh_volume(volume, request).mesh;
  for (const auto& r : mesh.regions)
    log::info() << "region " << r.name << ": " << r.tetrahedra << " tetrahedra, volume " << 100 * (r.volume_m3 / r.voxel_volume_m3 - 1)
                << " % off its voxels', smallest dihedral angle " << r.min_dihedral_deg << " deg";
  for (const auto& f : mesh.surfaces)
    log::detail() << "surface " << f.name << ": " << f.triangles << " triangles, neighbours' normals " << f.median_angle_deg
                  << " deg (median), " << f.p99_angle_deg << " deg (99th percentile); within " << f.max_distance_mm
                  << " mm of its label boundary";
  if (mesh.quality.inverted + mesh.quality.degenerate > 0 || !mesh.closed_manifold)
    throw std::runtime_error("the mesh has inverted or degenerate elements or an open boundary");
  fs::create_directories(file.parent_path());
  const fs::path partial = file.string() + ".partial" + std::to_string(::getpid()) + ".vtu";
  meshes::write_volume_mesh(mesh, partial);
  fs::rename(partial, file);  // whole or not at all, even with another fetouch meshing the same
  log::info() << mesh.tetrahedra.size() << " tetrahedra, smallest dihedral angle " << mesh.quality.min_dihedral_deg
              << " deg, volume " << 100 * (mesh.volume_m3 / mesh.segmented_volume_m3 - 1) << " % off the voxels', in "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s";
}

}  // namespace

std::optional<config::Scene> load_scene_or_report(const std::string& file) {
  try {
    return config::load_scene(file).scene;
  } catch (const config::SceneError& error) {
    for (const auto& d : error.diagnostics()) std::cerr << d.format() << "\n";
    return std::nullopt;
  }
}

meshes::MaskVolume mask_volume(const imaging::Mask& mask) {
  meshes::MaskVolume out;
  out.dimensions = mask.dimensions, out.spacing_mm = mask.spacing_mm, out.origin_mm = mask.origin_mm;
  out.direction = mask.direction, out.data = mask.data;
  return out;
}

meshes::MaskVolume label_map(const imaging::Volume<float>& volume) {
  meshes::MaskVolume out;
  out.dimensions = volume.dimensions, out.spacing_mm = volume.spacing_mm;
  out.origin_mm = volume.origin_mm, out.direction = volume.direction;
  out.data.resize(volume.data.size());
  for (std::size_t i = 0; i < volume.data.size(); ++i)
    out.data[i] = static_cast<std::uint8_t>(std::clamp(std::lround(volume.data[i]), 0L, 255L));
  return out;
}

imaging::PhantomSettings phantom_settings(const config::PhantomSource& source) {
  imaging::PhantomSettings p;
  p.seed = static_cast<std::uint32_t>(source.seed);
  p.spacing_mm = source.spacing_m * 1e3;
  for (int d = 0; d < 3; ++d) p.fetus_offset_mm[d] = source.fetus_offset_m[d] * 1e3;
  p.fetus_orientation = phantom_orientation(source.pose);
  p.gestational_age_weeks = source.gestational_age_weeks;
  return p;
}

std::optional<imaging::PhantomSettings::Orientation> phantom_orientation(const std::optional<config::FetalPose>& pose) {
  if (!pose) return std::nullopt;
  const config::FetalAxes axes = config::fetal_axes(*pose);
  return imaging::PhantomSettings::Orientation{axes.head, axes.back};
}

fs::path mesh_cache_dir() {
  if (const char* d = std::getenv("FETOUCH_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return fs::path(d) / "fetouch";
  if (const char* d = std::getenv("HOME"); d && *d) return fs::path(d) / ".cache" / "fetouch";
  return fs::temp_directory_path() / "fetouch-cache";
}

fs::path cached_mesh_path(const config::MeshSpec& spec) {
  std::ostringstream name;
  name << "mesh-" << std::hex << std::hash<std::string>{}(cache_key(spec)) << ".vtu";
  return mesh_cache_dir() / "meshes" / name.str();
}

config::MeshSpec mesh_scene_volume(const config::MeshSpec& spec) {
  if (spec.source != config::MeshSource::volume && spec.source != config::MeshSource::phantom) return spec;
  const fs::path file = cached_mesh_path(spec);
  int initialised = 0, rank = 0, ranks = 1;
  MPI_Initialized(&initialised);
  if (initialised) MPI_Comm_rank(MPI_COMM_WORLD, &rank), MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int ok = 1;
  std::string failure;
  if (rank == 0 && !fs::exists(file)) {
    try {
      mesh_into(spec, file);
    } catch (const std::exception& e) {
      ok = 0, failure = e.what();
    }
  }
  if (ranks > 1) MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!ok)
    throw std::runtime_error((spec.source == config::MeshSource::phantom ? std::string("the phantom") : spec.path.string()) +
                             ": could not be meshed: " + (rank == 0 ? failure : "(see rank 0)"));
  if (rank == 0 && fs::exists(file)) log::detail() << "the scene's volume mesh: " << file.string();
  config::MeshSpec out = spec;
  out.source = config::MeshSource::file;
  out.path = file;
  return out;
}

config::MeshSpec resolved_mesh_spec(const config::Scene& scene) {
  config::MeshSpec spec = scene.mesh;
  auto& m = spec.meshing;
  if (!m.refine_around_probes) return spec;
  const double inf = std::numeric_limits<double>::infinity();
  m.refine_balls.clear();
  for (std::size_t i = 0; i < scene.probes.size(); ++i) {
    const config::Probe& probe = scene.probes[i];
    if (probe.device.trajectory.empty()) continue;  // a PHANTOM or the mouse: no path known beforehand
    haptics::Trajectory path;
    try {
      path = read_probe_trajectory(probe.device.trajectory, probe.name, static_cast<int>(i));
    } catch (const std::exception& e) {
      throw std::runtime_error(scene.source.string() + ": meshing.refine.around_probes: " + e.what());
    }
    // A ball around this probe's path: the path's box, widened by the probe's radius.
    Eigen::Vector3d low(inf, inf, inf), high = -low;
    for (const Eigen::Vector3d& x : path.positions_m) low = low.cwiseMin(x), high = high.cwiseMax(x);
    const Eigen::Vector3d centre = (low + high) / 2;
    m.refine_balls.push_back({config::Vec3{centre[0], centre[1], centre[2]}, (high - low).norm() / 2 + probe.radius_m});
  }
  if (m.refine_balls.empty())
    throw std::runtime_error(scene.source.string() +
                             ": meshing.refine.around_probes: no probe has a trajectory (a replay or operator device) "
                             "to refine around; give refine.center_m and radius_m instead");
  return spec;
}

config::MeshSpec mesh_scene_volume(const config::Scene& scene) { return mesh_scene_volume(resolved_mesh_spec(scene)); }

}  // namespace fetouch::app
