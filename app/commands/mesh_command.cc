// `fetouch mesh`: a tetrahedral simulation mesh from an ultrasound volume or a label map
// (imaging/segmentation.h, meshes/volume_mesher.h), as .msh 4.1 and .vtu, with a quality report.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/commands/commands.h"
#include "app/error_text.h"
#include "app/exit_codes.h"
#include "app/output_guard.h"
#include "app/json_writer.h"
#include "app/log.h"
#include "app/mesh_pipeline.h"
#include "app/progress.h"
#include "app/scene_mesh.h"
#include "imaging/segmentation.h"
#include "imaging/volume_io.h"
#include "meshes/mesh_regions.h"
#include "meshes/volume_mesher.h"

namespace fetouch::app {

namespace {

namespace fs = std::filesystem;

struct MeshOptions {
  std::string volume, out = "tissue.msh";
  std::vector<int> labels;        // label map: these labels are the tissue
  std::vector<std::string> regions;  // label map: NAME=L1,L2 ... (their union is the tissue)
  bool fetus = false;             // the fetal segmentation pipeline
  std::optional<float> threshold;  // intensity threshold, in the image's units
  std::optional<double> threshold_percentile;  // or a percentile of the smoothed volume
  // (default: halfway between the 5th and 95th percentiles)
  std::string smoothing = "gaussian";
  std::string surface = "restricted";
  std::vector<std::string> region_sizes;  // NAME=MM, conforming only
  double smoothing_mm = 1.0;
  int closing = 2;
  double size_mm = 3;
  double min_dihedral_deg = 10;
  int partitions = 0;
  std::vector<double> refine;     // X Y Z RADIUS SIZE, mm, for each --refine
  bool json = false;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int run_mesh(const MeshOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(o.out);
  if (out.extension() != ".msh" && out.extension() != ".vtu") {
    std::cerr << "error: --out must end in .msh or .vtu (both are written): " << o.out << "\n";
    return kExitBadInput;
  }
  meshes::VolumeMesh mesh;
  std::vector<meshes::MeshRegion> regions;
  try {
    for (const std::string& text : o.regions) {
      regions.push_back(meshes::parse_region(text));
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: --regions " << e.what() << "\n";
    return kExitBadInput;
  }
  if (!regions.empty() && (o.fetus || !o.labels.empty())) {
    std::cerr << "error: --regions takes the labels of a label map itself; drop --labels and --fetus\n";
    return kExitBadInput;
  }
  if (o.threshold && o.threshold_percentile) {
    std::cerr << "error: give --threshold or --threshold-percentile, not both\n";
    return kExitBadInput;
  }
  std::vector<std::pair<std::string, double>> phases;
  float threshold_used = 0;
  bool thresholded = false;
  imaging::Volume<float> volume;
  try {
    log::info() << "reading " << o.volume;
    volume = imaging::read_volume(o.volume);
    phases.push_back({"reading", seconds_since(start)});
  } catch (const std::exception& e) {
    std::cerr << "error: " << naming(o.volume, e.what()) << "\n";
    return kExitBadInput;
  }
  MeshRequest request;
  auto& segmentation = request.segmentation;
  segmentation.labels = o.labels, segmentation.fetus = o.fetus, segmentation.smoothing_mm = o.smoothing_mm;
  segmentation.closing = o.closing;
  segmentation.threshold = o.threshold, segmentation.threshold_percentile = o.threshold_percentile;
  if (o.smoothing == "none") segmentation.smoothing = imaging::TissueSegmentation::Smoothing::none;
  if (o.smoothing == "median") segmentation.smoothing = imaging::TissueSegmentation::Smoothing::median;
  request.regions = regions;
  request.surface = o.surface == "contoured"    ? config::MeshSurface::contoured
                    : o.surface == "conforming" ? config::MeshSurface::conforming
                                                : config::MeshSurface::restricted;
  meshes::MeshingSettings& settings = request.settings;
  settings.element_size_mm = o.size_mm;
  settings.partitions = o.partitions;
  settings.min_dihedral_deg = o.min_dihedral_deg;
  for (const std::string& text : o.region_sizes) {
    const std::size_t equals = text.find('=');
    std::size_t at = regions.size();
    for (std::size_t r = 0; r < regions.size() && equals != std::string::npos; ++r)
      if (regions[r].name == text.substr(0, equals)) at = r;
    double size = 0;
    try {
      if (at < regions.size()) size = std::stod(text.substr(equals + 1));
    } catch (const std::exception&) {
    }
    if (at == regions.size() || !(size > 0) || o.surface != "conforming") {
      std::cerr << "error: --region-size " << text << ": expected NAME=MM for a region of --regions, with --surface conforming\n";
      return kExitBadInput;
    }
    settings.region_size_mm.resize(regions.size(), 0);
    settings.region_size_mm[at] = size;
  }
  // Each --refine a ball (a scene's `refine: {around_probes: true}` makes one per probe); the balls
  // share one size, as a scene's do.
  for (std::size_t at = 0; at + 5 <= o.refine.size(); at += 5) {
    settings.refine_balls.push_back({{o.refine[at], o.refine[at + 1], o.refine[at + 2]}, o.refine[at + 3]});
    if (at > 0 && o.refine[at + 4] != settings.refine_size_mm) {
      std::cerr << "error: --refine: every ball takes the same SIZE (" << settings.refine_size_mm << " mm, then "
                << o.refine[at + 4] << " mm)\n";
      return kExitBadInput;
    }
    settings.refine_size_mm = o.refine[at + 4];
  }
  try {
    Progress progress("meshing", 100, std::cerr, Progress::stderr_is_terminal());
    settings.progress = [&](const std::string& step, double done) {
      log::debug() << step;
      progress.update(static_cast<long>(100 * done));
    };
    log::info() << "segmenting and meshing";
    MeshOutcome outcome = mesh_volume(volume, request);
    progress.finish();
    mesh = std::move(outcome.mesh);
    thresholded = outcome.thresholded, threshold_used = outcome.threshold_used;
    if (thresholded) log::info() << "threshold " << threshold_used;
    phases.insert(phases.end(), outcome.phases.begin(), outcome.phases.end());
  } catch (const std::exception& e) {
    std::cerr << "error: " << o.volume << ": " << e.what() << "\n";
    return kExitBadInput;
  }
  fs::path msh = out, vtu = out;
  msh.replace_extension(".msh");
  vtu.replace_extension(".vtu");
  if (!mesh.quality_met) {
    // Not written where a good mesh is expected (nor over one): beside it, to look at.
    fs::path rejected = out;
    rejected.replace_extension(".rejected.vtu");
    try {
      if (out.has_parent_path()) fs::create_directories(out.parent_path());
      replace_when_written(rejected, [&](const fs::path& to) { meshes::write_volume_mesh(mesh, to); });
    } catch (const std::exception& e) {
      std::cerr << "error: " << e.what() << "\n";
    }
    std::string tried;
    for (const auto& a : mesh.attempts) tried += "\n  " + a;
    std::fprintf(stderr,
                 "error: %s: no mesh reached the quality asked, a smallest dihedral angle of %.1f deg and radius ratio of "
                 "%.2f (the best, %.1f deg and %.3f, by %s, is written as %s to look at; a smaller --size or a smoother "
                 "segmentation usually helps). Paths tried:%s\n",
                 o.volume.c_str(), o.min_dihedral_deg, meshes::MeshingSettings{}.min_radius_ratio, mesh.quality.min_dihedral_deg,
                 mesh.quality.min_radius_ratio, mesh.path.c_str(),
                 rejected.string().c_str(), tried.c_str());
    return kExitFailure;
  }
  const auto writing = std::chrono::steady_clock::now();
  try {
    if (out.has_parent_path()) fs::create_directories(out.parent_path());
    replace_when_written(msh, [&](const fs::path& to) { meshes::write_volume_mesh(mesh, to, o.partitions); });
    replace_when_written(vtu, [&](const fs::path& to) { meshes::write_volume_mesh(mesh, to); });
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitFailure;
  }
  phases.push_back({"writing", seconds_since(writing)});
  const double seconds = seconds_since(start);
  const auto& q = mesh.quality;
  const double volume_error = mesh.volume_m3 / mesh.segmented_volume_m3 - 1;
  std::ostringstream text;
  JsonWriter json(text);
  json.begin_object();
  json.key("volume").value(o.volume);
  json.key("msh").value(msh.string());
  json.key("vtu").value(vtu.string());
  json.key("nodes").value(static_cast<long>(mesh.nodes_m.size()));
  json.key("tetrahedra").value(static_cast<long>(mesh.tetrahedra.size()));
  json.key("boundary_triangles").value(static_cast<long>(mesh.boundary.size()));
  json.key("closed_manifold").value(mesh.closed_manifold);
  json.key("volume_m3").value(mesh.volume_m3);
  json.key("segmented_volume_m3").value(mesh.segmented_volume_m3);
  json.key("volume_error").value(volume_error);
  json.key("quality").begin_object();
  json.key("min_dihedral_deg").value(q.min_dihedral_deg);
  json.key("max_dihedral_deg").value(q.max_dihedral_deg);
  json.key("dihedral_histogram_10deg").begin_array();
  for (long c : q.dihedral_histogram) json.value(c);
  json.end_array();
  json.key("min_radius_ratio").value(q.min_radius_ratio);
  json.key("radius_ratio_histogram_0_1").begin_array();
  for (long c : q.radius_ratio_histogram) json.value(c);
  json.end_array();
  json.key("inverted").value(q.inverted);
  json.key("degenerate").value(q.degenerate);
  json.end_object();
  json.key("sliver_repair").begin_object();
  json.key("min_dihedral_before_deg").value(mesh.repair.min_dihedral_before_deg);
  json.key("peeled").value(mesh.repair.peeled);
  json.key("peeled_volume_m3").value(mesh.repair.peeled_volume);
  json.key("flips23").value(mesh.repair.flips23);
  json.key("flips32").value(mesh.repair.flips32);
  json.key("flips44").value(mesh.repair.flips44);
  json.key("edge_removals").value(mesh.repair.edge_removals);
  json.key("interface_caps_moved").value(mesh.repair.caps_moved);
  json.key("relocated").value(mesh.repair.relocated);
  json.end_object();
  json.key("surface_remeshed").value(mesh.surface_remeshed);
  json.key("surface_offset_mm").value(mesh.surface_offset_mm);
  json.key("path").value(mesh.path);
  json.key("paths_tried").begin_array();
  for (const auto& a : mesh.attempts) json.value(a);
  json.end_array();
  json.key("min_dihedral_asked_deg").value(o.min_dihedral_deg);
  if (thresholded) json.key("threshold").value(static_cast<double>(threshold_used));
  json.key("phases_seconds").begin_object();
  for (const auto& [phase, t] : phases) json.key(phase).value(t);
  json.end_object();
  json.key("regions").begin_array();
  for (const auto& r : mesh.regions) {
    json.begin_object();
    json.key("name").value(r.name);
    json.key("tetrahedra").value(r.tetrahedra);
    json.key("volume_m3").value(r.volume_m3);
    json.key("voxel_volume_m3").value(r.voxel_volume_m3);
    json.key("min_dihedral_deg").value(r.min_dihedral_deg);
    json.key("outer_triangles").value(r.outer_triangles);
    json.end_object();
  }
  json.end_array();
  json.key("surfaces").begin_array();
  for (const auto& f : mesh.surfaces) {
    json.begin_object();
    json.key("name").value(f.name);
    json.key("triangles").value(f.triangles);
    json.key("median_neighbour_angle_deg").value(f.median_angle_deg);
    json.key("p99_neighbour_angle_deg").value(f.p99_angle_deg);
    json.key("max_neighbour_angle_deg").value(f.max_angle_deg);
    json.key("max_distance_to_labels_mm").value(f.max_distance_mm);
    json.end_object();
  }
  json.end_array();
  json.key("interface_triangles").value(mesh.interface_triangles);
  json.key("interfaces").begin_object();  // surface group name: its triangles
  for (const auto& [name, faces] : meshes::interface_groups(mesh)) json.key(name).value(faces);
  json.end_object();
  json.key("seconds").value(seconds);
  json.end_object();
  if (o.json) {
    std::cout << text.str() << "\n";
  } else {
    std::printf("%zu tetrahedra, %zu nodes, %zu boundary triangles (%s) in %.1f s\n", mesh.tetrahedra.size(),
                mesh.nodes_m.size(), mesh.boundary.size(),
                mesh.closed_manifold ? "closed, manifold" : "NOT closed and manifold", seconds);
    std::printf("  volume %.4g ml against %.4g ml segmented (%+.2f %%; boundary moved out %.2f mm to keep it)\n",
                mesh.volume_m3 * 1e6, mesh.segmented_volume_m3 * 1e6, 100 * volume_error, mesh.surface_offset_mm);
    std::printf("  dihedral angles %.1f to %.1f deg, radius ratio from %.3f, %ld inverted, %ld degenerate\n",
                q.min_dihedral_deg, q.max_dihedral_deg, q.min_radius_ratio, q.inverted, q.degenerate);
    const auto& r = mesh.repair;
    std::printf("  sliver repair: smallest dihedral %.1f -> %.1f deg (%d peeled, %d 2-3, %d 3-2 and %d 4-4 flips, %d edges removed, %d interface caps moved, %d nodes moved)\n",
                r.min_dihedral_before_deg, r.min_dihedral_after_deg, r.peeled, r.flips23, r.flips32, r.flips44, r.edge_removals, r.caps_moved,
                r.relocated);
    for (const auto& region : mesh.regions)
      std::printf("  region %s: %ld tetrahedra, %.4g ml against %.4g ml of voxels (%+.2f %%), smallest dihedral %.1f deg, %ld outer triangles\n",
                  region.name.c_str(), region.tetrahedra, region.volume_m3 * 1e6, region.voxel_volume_m3 * 1e6,
                  100 * (region.volume_m3 / region.voxel_volume_m3 - 1), region.min_dihedral_deg, region.outer_triangles);
    if (!mesh.regions.empty()) {
      std::string groups;
      for (const auto& [name, faces] : meshes::interface_groups(mesh))
        groups += (groups.empty() ? "" : ", ") + name + " " + std::to_string(faces);
      std::printf("  %ld interface triangles between regions (surface groups: %s)\n", mesh.interface_triangles,
                  groups.empty() ? "none" : groups.c_str());
    }
    for (const auto& f : mesh.surfaces)
      std::printf("  surface %s: %ld triangles, neighbours' normals %.1f deg median, %.1f deg 99th percentile; within %.2f mm of "
                  "its label boundary\n",
                  f.name.c_str(), f.triangles, f.median_angle_deg, f.p99_angle_deg, f.max_distance_mm);
    std::printf("  made by: %s%s\n", mesh.path.c_str(), mesh.attempts.size() > 1 ? " (after the paths before it failed or fell short)" : "");
    if (mesh.attempts.size() > 1)
      for (const auto& a : mesh.attempts) std::printf("    tried %s\n", a.c_str());
    std::string timing;
    for (const auto& [phase, t] : phases) {
      char part[64];
      std::snprintf(part, sizeof part, "%s%s %.1f s", timing.empty() ? "" : ", ", phase.c_str(), t);
      timing += part;
    }
    std::printf("  time: %s\n", timing.c_str());
    std::printf("  wrote %s and %s (open the .vtu in ParaView)\n", msh.string().c_str(), vtu.string().c_str());
  }
  if (std::abs(volume_error) > 0.03)
    log::warning() << "the mesh's volume is " << 100 * volume_error << " % off the segmented voxels' (flat triangles cut "
                << "curved surfaces: a smaller --size follows them closer)";
  return q.inverted == 0 && q.degenerate == 0 && mesh.closed_manifold ? kExitOk : kExitFailure;
}

}  // namespace

void add_mesh_command(CLI::App& parent, int& exit_code) {
  auto o = std::make_shared<MeshOptions>();
  CLI::App* cmd = parent.add_subcommand("mesh", "Mesh an ultrasound volume or label map into tetrahedra");
  cmd->footer(
      "Segments the volume (a label map with --labels, the fetal pipeline with --fetus, otherwise a\n"
      "threshold after smoothing: the largest region, closed and hole-filled); a segmentation nowhere\n"
      "thicker than a quarter of --size is refused. CGAL samples its surface by Delaunay refinement\n"
      "(triangles of --size, angles of 25 deg or more, within half a voxel of it; closed, manifold and\n"
      "never crossing itself) and Gmsh's Delaunay mesher fills it (HXT where that misses the angle);\n"
      "then the sliver repair, and the boundary moved out to\n"
      "the segmented volume. When that misses the quality, the same with smaller triangles, then\n"
      "surfaces contoured by VTK (remeshed by Gmsh, as they are, smoother); the report names the path\n"
      "and each phase's time. Writes MESH.msh (4.1; physical groups `surface` and `tissue`) and\n"
      "MESH.vtu, in metres. Exit 0 with a closed, manifold boundary, no inverted or degenerate element,\n"
      "the smallest dihedral angle at least --min-dihedral and every radius ratio at least 0.1; exit 1\n"
      "when no path reached that (the best mesh written as MESH.rejected.vtu, MESH.msh and MESH.vtu\n"
      "untouched); exit 2 when the input cannot be meshed at all (the reason, and where Gmsh names one,\n"
      "the place in mm).\n"
      "With --regions, one mesh of the regions' union whose elements each take the region covering most\n"
      "of them (the regions share their interfaces node for node; an interface follows element faces),\n"
      "volume groups named as given, surface groups NAME_outer and one per interface, A_B (the\n"
      "regions in the order given), and a report per region. With --surface conforming the label map\n"
      "itself is meshed: every region a subdomain of one CGAL mesh, each interface a smooth surface of\n"
      "its own, the curves where three regions meet kept, sizes per region (--region-size NAME=MM);\n"
      "the report gives each surface's smoothness and distance to its labels (docs/meshing.md). Its\n"
      "exit 0 asks the smallest dihedral angle only; the radius ratio is reported, not asked (a few\n"
      "flat elements stay after exudation: on the phantom 6 of 31,024 under 0.1, the worst 0.06).\n"
      "Example: fetouch mesh phantom/phantom_labels.mha --labels 3 4 5 6 --size 3 --out fetus.msh\n"
      "         fetouch mesh phantom/phantom_labels.mha --regions wall=1 fluid=2 fetus=3,4,5,6 --size 4");
  cmd->add_option("volume", o->volume, "Volume (.mha, .mhd, .vti, .nrrd, .nii, .nii.gz, .hdr) or a folder with a DICOM series")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--out", o->out, "Mesh file (.msh or .vtu; both are written)")->capture_default_str();
  cmd->add_option("--labels", o->labels, "The labels that make the tissue (label maps)");
  cmd->add_option("--regions", o->regions,
                  "Regions of a label map, NAME=L1,L2 each: one conforming mesh of their union, each element in the "
                  "region covering most of it (volume groups NAME, surfaces NAME_outer and A_B per interface)");
  cmd->add_option("--region-size", o->region_sizes, "With --surface conforming: a region's element size, NAME=MM (others: --size)");
  cmd->add_flag("--fetus", o->fetus, "Segment the fetus of a fetal ultrasound volume");
  cmd->add_option("--threshold", o->threshold,
                  "Intensity threshold in the image's units (Hounsfield units for a CT; default: between the 5th and 95th "
                  "percentiles)");
  cmd->add_option("--threshold-percentile", o->threshold_percentile,
                  "Threshold at this percentile of the smoothed volume's intensities, 0 to 100")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--surface", o->surface,
                  "How the surface is made: restricted (CGAL's restricted Delaunay surface first, then the others), "
                  "contoured (only VTK's contour, remeshed by Gmsh or kept: the mesher before CGAL), or conforming "
                  "(with --regions: every region a subdomain of one CGAL mesh, each interface a smooth surface of its own)")
      ->check(CLI::IsMember({"restricted", "contoured", "conforming"}))
      ->capture_default_str();
  cmd->add_option("--smoothing", o->smoothing, "Speckle filter before the threshold: none, gaussian or median (3x3x3)")
      ->check(CLI::IsMember({"none", "gaussian", "median"}))
      ->capture_default_str();
  cmd->add_option("--smooth", o->smoothing_mm, "Gaussian smoothing before the threshold, mm")->check(CLI::Range(0.0, 50.0))->capture_default_str();
  cmd->add_option("--close", o->closing, "Closing radius, voxels")->check(CLI::Range(0, 10))->capture_default_str();
  cmd->add_option("--size", o->size_mm, "Target element size, mm")->check(CLI::Range(0.01, 500.0))->capture_default_str();
  cmd->add_option("--min-dihedral", o->min_dihedral_deg,
                  "Smallest dihedral angle a written mesh may have, deg (else exit 1, the best mesh written as "
                  "MESH.rejected.vtu)")
      ->check(CLI::Range(1.0, 35.0))
      ->capture_default_str();
  cmd->add_option("--refine", o->refine,
                  "Finer elements near a point: X Y Z RADIUS SIZE (mm; grading over one more radius); repeatable, one "
                  "ball each, the same SIZE")
      ->expected(5)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--partitions", o->partitions, "METIS partitions in the .msh")->check(CLI::Range(0, 1024));
  cmd->add_flag("--json", o->json, "Print the report as JSON on stdout");
  cmd->callback([o, &exit_code]() { exit_code = run_mesh(*o); });
}

}  // namespace fetouch::app
