// `fetouch check SCENE...`: validate scene files and summarise them.
//
// Two levels: the scene file itself (schema, types, ranges, cross-field rules; config/), then, unless
// --no-mesh, what it points at: the mesh is read (Gmsh or VTK) and built in deal.II, the volume's header
// is read, and every physical group the scene names must exist in the mesh.
#include <CLI/CLI.hpp>

#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands/commands.h"
#include "app/exit_codes.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/mpi_session.h"
#include "app/progress.h"
#include "app/recording.h"
#include "app/mesh_pipeline.h"
#include "app/scene_mesh.h"
#include "config/scene_loader.h"
#include "fem/physical_problem.h"
#include "fem/tissue_mesh.h"
#include "fem/tissue_model.h"
#include "imaging/volume_info.h"
#include "meshes/mesh_summary.h"

namespace fetouch::app {

namespace {

struct CheckOptions {
  std::vector<std::string> scenes;
  bool json = false;
  bool no_mesh = false;
};

// What `check` learnt about one scene file.
struct SceneReport {
  std::string file;
  bool valid = false;
  std::vector<config::Diagnostic> errors;
  std::vector<config::Diagnostic> warnings;
  std::unique_ptr<config::Scene> scene;
  std::optional<meshes::MeshSummary> mesh_file;
  std::optional<fem::TissueMeshInfo> tissue;
  fem::RegionMaterials regions;  // the scene's material of each of tissue's regions
  std::optional<imaging::VolumeInfo> volume;
};

std::string number(double value, int precision = 4) {
  std::ostringstream out;
  out << std::setprecision(precision) << value;
  return out.str();
}

std::string vec(const config::Vec3& v) {
  return "[" + number(v[0]) + ", " + number(v[1]) + ", " + number(v[2]) + "]";
}

config::Diagnostic diagnostic_at(const std::string& file, const config::SourceLocation& where,
                                 const std::string& key, const std::string& message) {
  config::Diagnostic d;
  d.file = file, d.line = where.line, d.column = where.column, d.key = key, d.message = message;
  return d;
}

// Names that the scene expects the mesh to define, checked against the mesh's boundary regions.
void check_group_names(SceneReport& report, const std::map<std::string, unsigned int>& available) {
  std::vector<std::string> names;
  for (const auto& [name, id] : available) names.push_back(name);
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  const config::Scene& scene = *report.scene;
  for (size_t i = 0; i < scene.boundary.size(); ++i) {
    const auto& region = scene.boundary[i];
    if (region.select.kind != config::SelectorKind::physical_group) continue;
    if (available.count(region.select.physical_group)) continue;
    std::string message = "the mesh has no boundary region named '" +
                           region.select.physical_group + "'";
    const std::string suggestion = config::closest_match(region.select.physical_group, names);
    if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
    message += list.empty() ? " (the mesh names none)" : " (it has " + list + ")";
    report.errors.push_back(diagnostic_at(report.file, region.where,
                                          "boundary[" + std::to_string(i) +
                                              "].select.physical_group",
                                          message));
  }
  if (scene.effects.has(config::Effect::cavity) && scene.effects.cavity_regions.empty() &&
      !available.count(scene.effects.cavity_surface))
    report.errors.push_back(diagnostic_at(
        report.file, scene.mesh.where, "effects.cavity.surface",
        "the mesh has no boundary region named '" + scene.effects.cavity_surface + "'" +
            (list.empty() ? std::string(" (the mesh names none)") : " (it has " + list + ")")));
}

void check_referenced_data(SceneReport& report) {
  const config::Scene& scene = *report.scene;
  const config::MeshSpec& mesh = scene.mesh;
  // The mesh in deal.II: its boundary and volume regions against the names the scene uses.
  const auto inspect = [&](const config::MeshSpec& spec) {
    log::detail() << "building the mesh in deal.II";
    report.tissue = fem::inspect_tissue_mesh(spec);
    check_group_names(report, report.tissue->boundary_ids);
    report.regions = fem::assign_region_materials(scene, *report.tissue);
    for (const std::string& name : scene.effects.cavity_regions)
      if (!fem::find_region(*report.tissue, name)) {
        std::string regions;
        for (const auto& region : report.tissue->regions) regions += (regions.empty() ? "" : ", ") + fem::describe_region(region);
        report.errors.push_back(diagnostic_at(report.file, scene.mesh.where, "effects.cavity.regions",
                                              "the mesh has no volume region '" + name + "' (its regions: " + regions + ")"));
      }
    for (const config::Diagnostic& d : report.regions.problems)
      report.errors.push_back(diagnostic_at(report.file, {d.line, d.column}, d.key, d.message));
    if (!report.errors.empty()) return;
    // The tissue as a session builds it: its boundary selectors select faces, and its supports hold
    // every piece (fem::PhysicalProblem otherwise, which a replay would fail on with exit 1).
    log::detail() << "building the tissue model";
    config::Scene built = scene;
    built.mesh = spec;
    ensure_mpi();
    try {
      fem::build_tissue_model(built);
    } catch (const fem::PhysicalProblem& e) {
      report.errors.push_back(diagnostic_at(report.file, scene.mesh.where, "boundary",
                                            std::string("a session would fail: ") + e.what()));
    } catch (const std::exception& e) {
      report.errors.push_back(diagnostic_at(report.file, scene.mesh.where, "mesh", e.what()));
    }
  };
  try {
    if (mesh.source == config::MeshSource::volume) report.volume = imaging::read_volume_info(mesh.path);
    if (mesh.source == config::MeshSource::volume || mesh.source == config::MeshSource::phantom) {
      // Meshed when first used: once it has been, the cached mesh tells the regions.
      config::MeshSpec cached = mesh;
      cached.source = config::MeshSource::file, cached.path = cached_mesh_path(mesh);
      if (std::filesystem::exists(cached.path)) inspect(cached);
      return;
    }
    if (mesh.source == config::MeshSource::file) {
      log::detail() << "reading " << mesh.path.string();
      report.mesh_file = meshes::read_mesh_summary(mesh.path);
    }
    inspect(mesh);
  } catch (const std::exception& e) {
    report.errors.push_back(diagnostic_at(report.file, mesh.where,
                                          mesh.source == config::MeshSource::volume ? "mesh.volume"
                                                                                     : "mesh",
                                          e.what()));
  }
}

SceneReport check_one(const std::string& file, bool no_mesh) {
  SceneReport report;
  report.file = file;
  try {
    config::LoadedScene loaded = config::load_scene(file);
    report.scene = std::make_unique<config::Scene>(std::move(loaded.scene));
    report.warnings = std::move(loaded.warnings);
    report.scene->mesh = resolved_mesh_spec(*report.scene);  // the probes' refinement ball, as a session's
  } catch (const config::SceneError& error) {
    for (const auto& d : error.diagnostics())
      (d.severity == config::Diagnostic::Severity::error ? report.errors : report.warnings).push_back(d);
    return report;
  } catch (const std::runtime_error& e) {
    report.errors.push_back(diagnostic_at(file, report.scene->mesh.where, "mesh.meshing.refine", e.what()));
    return report;
  }
  if (!no_mesh) check_referenced_data(report);
  // Each probe's trajectory read and checked as a replay would (a FIFO, NaN or a unit slip is
  // found here, not minutes into a session).
  for (std::size_t i = 0; i < report.scene->probes.size(); ++i) {
    const config::Probe& probe = report.scene->probes[i];
    if (probe.device.trajectory.empty()) continue;
    try {
      read_probe_trajectory(probe.device.trajectory, probe.name, static_cast<int>(i));
    } catch (const std::exception& e) {
      report.errors.push_back(diagnostic_at(report.file, probe.where, "probes[" + std::to_string(i) + "].device.trajectory", e.what()));
    }
  }
  report.valid = report.errors.empty();
  return report;
}

// ---- text summary -------------------------------------------------------------------------------

std::string describe_mesh(const SceneReport& r) {
  const config::MeshSpec& m = r.scene->mesh;
  std::string text;
  switch (m.source) {
    case config::MeshSource::generated: {
      const auto& g = m.generated;
      text = std::string("generated ") + config::to_string(g.shape);
      if (g.shape == config::GeneratedShape::box)
        text += " " + number(g.size_m[0]) + " x " + number(g.size_m[1]) + " x " +
                number(g.size_m[2]) + " m";
      else if (g.shape == config::GeneratedShape::ball)
        text += " of radius " + number(g.radius_m) + " m";
      else
        text += " of radii " + number(g.inner_radius_m) + " and " + number(g.radius_m) + " m";
      break;
    }
    case config::MeshSource::file: text = m.path.string(); break;
    case config::MeshSource::volume:
      text = "meshed from " + m.path.string() + " at " + meshing_sizes_text(m.meshing);
      break;
    case config::MeshSource::phantom:
      text = "the synthetic phantom (seed " + std::to_string(m.phantom.seed) + ", " + number(m.phantom.spacing_m * 1e3) +
             " mm voxels) meshed at " + meshing_sizes_text(m.meshing);
      break;
  }
  std::string element = config::to_string(m.element);
  for (auto& c : element) c = static_cast<char>(std::toupper(c));
  text += ", " + element + " elements";
  if (r.tissue)
    text += "; " + std::to_string(r.tissue->cells) + (r.tissue->simplex ? " tetrahedra, " : " hexahedra, ") +
            std::to_string(r.tissue->vertices) + " vertices, " + number(r.tissue->volume_m3) +
            " m^3, cell size " + number(r.tissue->min_diameter_m) + " to " +
            number(r.tissue->max_diameter_m) + " m";
  if (r.volume)
    text += "; volume " + std::to_string(r.volume->dimensions[0]) + " x " +
            std::to_string(r.volume->dimensions[1]) + " x " +
            std::to_string(r.volume->dimensions[2]) + " voxels of " +
            number(r.volume->spacing_mm[0]) + " x " + number(r.volume->spacing_mm[1]) + " x " +
            number(r.volume->spacing_mm[2]) + " mm (" + r.volume->format + ")";
  if (r.mesh_file && !r.tissue)
    text += "; " + std::to_string(r.mesh_file->nodes) + " nodes, " +
            std::to_string(r.mesh_file->count("tetrahedron")) + " tetrahedra";
  return text;
}

std::string describe_material(const config::Material& m) {
  std::string text = config::to_string(m.model);
  if (m.model == config::MaterialModel::mooney_rivlin)
    text += ", c10 = " + number(m.c10_pa) + " Pa, c01 = " + number(m.c01_pa) +
            " Pa, K = " + number(m.bulk_modulus_pa) + " Pa";
  else
    text += ", E = " + number(m.youngs_modulus_pa) + " Pa, nu = " + number(m.poisson_ratio);
  text += ", density " + number(m.density_kg_per_m3) + " kg/m^3";
  return text;
}

std::string describe_effects(const config::Effects& e) {
  std::string text = "elasticity";
  for (auto effect : e.listed)
    if (effect != config::Effect::elasticity) text += std::string(", ") + config::to_string(effect);
  return text;
}

std::string describe_region(const config::BoundaryRegion& b) {
  std::string text = b.name + ": " + config::to_string(b.type);
  if (b.type == config::BoundaryType::traction) {
    text += " " + vec(b.traction_pa) + " Pa";
  } else if (!(b.components[0] && b.components[1] && b.components[2])) {
    text += " (u = 0 along";
    for (int axis = 0; axis < 3; ++axis)
      if (b.components[axis]) text += std::string(" ") + "xyz"[axis];
    text += ")";
  }
  switch (b.select.kind) {
    case config::SelectorKind::box:
      text += " on box " + vec(b.select.box_min) + " to " + vec(b.select.box_max);
      break;
    case config::SelectorKind::physical_group:
      text += " on physical group '" + b.select.physical_group + "'";
      break;
    case config::SelectorKind::plane:
      text += " on plane through " + vec(b.select.plane_point) + " normal " +
              vec(b.select.plane_normal);
      break;
  }
  return text;
}

std::string describe_device(const config::Device& d) {
  std::string text = config::to_string(d.type);
  if (!d.trajectory.empty()) text += " " + d.trajectory.filename().string();
  if (d.type == config::DeviceType::phantom)
    text += d.phantom_name.empty() ? " (default device)" : " '" + d.phantom_name + "'";
  return text;
}

void print_text(const SceneReport& r, std::ostream& out) {
  if (!r.valid) return;
  const config::Scene& s = *r.scene;
  out << r.file << ": valid\n";
  const auto row = [&](const char* label, const std::string& text) {
    out << "  " << std::left << std::setw(10) << label << text << '\n';
  };
  if (!s.name.empty()) row("scene", s.name + (s.description.empty() ? "" : ": " + s.description));
  row("mesh", describe_mesh(r));
  if ((r.tissue && r.tissue->regions.size() > 1) || !s.materials.empty()) {
    // Each region with its volume and the material it takes (known once the mesh was read).
    if (r.tissue) {
      for (const auto& region : r.tissue->regions) {
        const int index = r.regions.of_region.at(region.material_id);
        row("region", fem::describe_region(region) + ": " + std::to_string(region.cells) + " cells, " +
                          number(region.volume_m3 * 1e6) + " cm^3; " +
                          describe_material(index < 0 ? s.material : s.materials[std::size_t(index)].material));
      }
    } else {
      if (s.material_given) row("material", describe_material(s.material) + " (regions not named below)");
      for (const auto& m : s.materials) row("material", m.region + ": " + describe_material(m.material));
    }
  } else {
    row("material", describe_material(s.material));
  }
  row("effects", describe_effects(s.effects));
  for (const auto& b : s.boundary) row("boundary", describe_region(b));
  std::string newton = number(s.solver.newton_relative_tolerance);
  row("solver", number(s.solver.rate_hz) + " Hz, Newton to " + newton + " relative (at most " +
                    std::to_string(s.solver.newton_max_iterations) + " iterations" +
                    (s.solver.line_search ? ", line search" : "") + "), linear solver " +
                    config::to_string(s.solver.linear_solver));
  const auto& h = s.haptics;
  std::string local_model = config::to_string(h.local_model);
  for (auto& c : local_model) c = static_cast<char>(std::toupper(c));
  std::string hold = config::to_string(h.hold);
  for (auto& c : hold) c = static_cast<char>(std::toupper(c));
  row("haptics", number(h.rate_hz) + " Hz (N = " + std::to_string(h.ratio(s.solver)) + "), " +
                     local_model + " local model, " + hold + ", gains " +
                     (h.automatic_gains ? "auto (margin " + number(100 * h.robustness_margin) + " %)"
                                        : "Kh = " + number(h.proportional_n_per_m) + " N/m" +
                                              (h.integral_n_per_m > 0
                                                   ? ", I = " + number(h.integral_n_per_m) + " N/m"
                                                   : "")) +
                     ", max force " + number(h.max_force_n) + " N" +
                     (h.coupling ? "" : ", coupling between probes off"));
  for (const auto& p : s.probes)
    row("probe", p.name + ": " + describe_device(p.device) + ", radius " +
                     number(p.radius_m * 1e3) + " mm");
}

// ---- JSON ---------------------------------------------------------------------------------------

void write_diagnostics(JsonWriter& json, const std::vector<config::Diagnostic>& list) {
  json.begin_array();
  for (const auto& d : list) {
    json.begin_object();
    json.key("file").value(d.file);
    json.key("line").value(d.line);
    json.key("column").value(d.column);
    json.key("key").value(d.key);
    json.key("message").value(d.message);
    json.end_object();
  }
  json.end_array();
}

void write_json(const std::vector<SceneReport>& reports, std::ostream& out) {
  JsonWriter json(out);
  json.begin_object();
  json.key("scenes").begin_array();
  for (const auto& r : reports) {
    json.begin_object();
    json.key("file").value(r.file);
    json.key("valid").value(r.valid);
    json.key("errors");
    write_diagnostics(json, r.errors);
    json.key("warnings");
    write_diagnostics(json, r.warnings);
    if (r.valid) {
      const config::Scene& s = *r.scene;
      json.key("name").value(s.name);
      json.key("mesh").begin_object();
      json.key("source").value(config::to_string(s.mesh.source));
      json.key("element").value(config::to_string(s.mesh.element));
      if (r.tissue) {
        json.key("cells").value(r.tissue->cells);
        json.key("vertices").value(r.tissue->vertices);
        json.key("volume_m3").value(r.tissue->volume_m3);
        json.key("simplex").value(r.tissue->simplex);
        json.key("boundary_regions").begin_array();
        for (const auto& [name, id] : r.tissue->boundary_ids) json.value(name);
        json.end_array();
      }
      if (r.volume) {
        json.key("voxels").begin_array();
        for (int d : r.volume->dimensions) json.value(d);
        json.end_array();
        json.key("spacing_mm").begin_array();
        for (double d : r.volume->spacing_mm) json.value(d);
        json.end_array();
      }
      json.end_object();
      json.key("material").begin_object();
      json.key("model").value(config::to_string(s.material.model));
      json.key("youngs_modulus_pa").value(s.material.youngs_modulus_pa);
      json.key("poisson_ratio").value(s.material.poisson_ratio);
      json.key("density_kg_per_m3").value(s.material.density_kg_per_m3);
      json.end_object();
      json.key("materials").begin_object();  // by region, as written
      for (const auto& m : s.materials) {
        json.key(m.region).begin_object();
        json.key("model").value(config::to_string(m.material.model));
        json.key("youngs_modulus_pa").value(m.material.youngs_modulus_pa);
        json.key("poisson_ratio").value(m.material.poisson_ratio);
        json.key("density_kg_per_m3").value(m.material.density_kg_per_m3);
        json.end_object();
      }
      json.end_object();
      if (r.tissue) {
        json.key("regions").begin_array();
        for (const auto& region : r.tissue->regions) {
          json.begin_object();
          json.key("material_id").value(static_cast<long>(region.material_id));
          json.key("name").value(region.name);
          json.key("cells").value(static_cast<long>(region.cells));
          json.key("volume_m3").value(region.volume_m3);
          const int index = r.regions.of_region.at(region.material_id);
          json.key("material").value(index < 0 ? std::string("material") : "materials." + s.materials[std::size_t(index)].region);
          json.end_object();
        }
        json.end_array();
      }
      json.key("effects").begin_array();
      json.value("elasticity");
      for (auto e : s.effects.listed)
        if (e != config::Effect::elasticity) json.value(config::to_string(e));
      json.end_array();
      json.key("boundary_regions").value(static_cast<long>(s.boundary.size()));
      json.key("solver_rate_hz").value(s.solver.rate_hz);
      json.key("haptic_rate_hz").value(s.haptics.rate_hz);
      json.key("ratio").value(s.haptics.ratio(s.solver));
      json.key("local_model").value(config::to_string(s.haptics.local_model));
      json.key("hold").value(config::to_string(s.haptics.hold));
      json.key("probes").begin_array();
      for (const auto& p : s.probes) {
        json.begin_object();
        json.key("name").value(p.name);
        json.key("device").value(config::to_string(p.device.type));
        json.key("radius_m").value(p.radius_m);
        json.end_object();
      }
      json.end_array();
    }
    json.end_object();
  }
  json.end_array();
  json.end_object();
}

int run_check(const CheckOptions& options) {
  std::vector<SceneReport> reports;
  std::optional<Progress> progress;  // only worth showing for many scenes
  if (options.scenes.size() > 3)
    progress.emplace("checking scenes", static_cast<long>(options.scenes.size()), std::cerr,
                     Progress::stderr_is_terminal());
  for (const auto& file : options.scenes) {
    log::detail() << "checking " << file;
    reports.push_back(check_one(file, options.no_mesh));
    if (progress) progress->update(static_cast<long>(reports.size()));
  }
  if (progress) progress->finish();

  bool all_valid = true;
  for (const auto& r : reports) {
    all_valid = all_valid && r.valid;
    for (const auto& d : r.errors) std::cerr << d.format() << '\n';
    if (log::enabled(log::Level::warning))
      for (const auto& d : r.warnings) std::cerr << d.format() << '\n';
  }
  if (options.json) {
    write_json(reports, std::cout);
  } else {
    for (const auto& r : reports) print_text(r, std::cout);
  }
  if (!all_valid) {
    long invalid = 0;
    for (const auto& r : reports) invalid += r.valid ? 0 : 1;
    log::error() << invalid << " of " << reports.size() << " scene file"
                 << (reports.size() == 1 ? "" : "s") << " rejected; see docs/scenes.md for every key";
  }
  return all_valid ? kExitOk : kExitBadInput;
}

}  // namespace

void add_check_command(CLI::App& parent, int& exit_code) {
  auto options = std::make_shared<CheckOptions>();
  CLI::App* check = parent.add_subcommand("check", "Validate scene files and summarise them");
  check->footer(
      "Reports every error with file:line:column and the key, then reads the mesh or volume\n"
      "the scene names and builds the mesh in deal.II. Exit code 2 if any scene is rejected.\n"
      "Example: fetouch check config/scenes/*.yaml");
  check->add_option("scenes", options->scenes, "Scene files (YAML), e.g. config/scenes/*.yaml")
      ->required();
  check->add_flag("--json", options->json, "Print a JSON report on stdout instead of the summary");
  check->add_flag("--no-mesh", options->no_mesh,
                  "Validate the scene file only; do not read the mesh or volume it names");
  check->callback([options, &exit_code]() { exit_code = run_check(*options); });
}

}  // namespace fetouch::app
