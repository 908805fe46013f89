#include "meshes/volume_mesher.h"

#include "meshes/gmsh_fill.h"
#include "meshes/mask_thickness.h"
#include "meshes/restricted_surface.h"
#include "meshes/surface_extraction.h"
#include "meshes/tet_repair.h"

#include <gmsh.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCleanPolyData.h>
#include <vtkFeatureEdges.h>
#include <vtkFillHolesFilter.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkMassProperties.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkPolyDataNormals.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkFieldData.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <cstdlib>
#include <cmath>
#include <map>
#include <stdexcept>

namespace fetouch::meshes {

namespace {

long open_edges(vtkPolyData* surface) {
  auto edges = vtkSmartPointer<vtkFeatureEdges>::New();
  edges->SetInputData(surface);
  edges->BoundaryEdgesOn();
  edges->NonManifoldEdgesOn();
  edges->FeatureEdgesOff();
  edges->ManifoldEdgesOff();
  edges->Update();
  return edges->GetOutput()->GetNumberOfCells();
}

// The quality every mesh written with exit 0 has.
bool meets(const QualityReport& q, const MeshingSettings& s) {
  return q.min_dihedral_deg >= s.min_dihedral_deg && q.min_radius_ratio >= s.min_radius_ratio;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void report(const MeshingSettings& s, const std::string& step, double done) {
  if (s.progress) s.progress(step, done);
}

// Nodes and triangles as VTK's polygonal data.
vtkSmartPointer<vtkPolyData> triangle_surface(const std::vector<Point3>& nodes, const std::vector<Triangle>& triangles) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  for (const auto& p : nodes) points->InsertNextPoint(p.data());
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& t : triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    cells->InsertNextCell(3, ids);
  }
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  surface->SetPolys(cells);
  return surface;
}

// Refuses settings that make no sense or a mesh too large for the memory, from the volume to fill.
void check_settings(double volume_mm3, const MeshingSettings& s) {
  if (!(s.element_size_mm > 0)) throw std::runtime_error("meshing: the element size must be positive");
  if (!s.refine_balls.empty() && !(s.refine_size_mm > 0))
    throw std::runtime_error("meshing: the refinement size must be positive");
  for (const auto& ball : s.refine_balls)
    if (!(ball.radius_mm > 0)) throw std::runtime_error("meshing: a refinement ball's radius must be positive");
  // A regular tetrahedron of edge a has a volume of a^3 / (6 sqrt 2).
  const auto tetrahedra_in = [](double v, double size_mm) { return v / (std::pow(size_mm, 3) / (6 * std::sqrt(2.0))); };
  double estimate = tetrahedra_in(volume_mm3, s.element_size_mm);
  for (const auto& ball : s.refine_balls)
    estimate += tetrahedra_in(4 * M_PI / 3 * std::pow(2 * ball.radius_mm, 3), s.refine_size_mm);
  if (estimate > 2e7)
    throw std::runtime_error("meshing: an element size of " + std::to_string(s.element_size_mm) + " mm" +
                             (!s.refine_balls.empty() ? " (" + std::to_string(s.refine_size_mm) + " mm refined)" : "") +
                             " would make about " + std::to_string(static_cast<long>(estimate)) +
                             " tetrahedra, more than memory allows (20 million)");
}

// A mesh as a mesher left it, finished: the boundary back out to the segmented volume (tet_repair.h;
// by a tenth of an element at most), the slivers left peeled, flipped away or relocated, then the
// boundary as the elements have it and the quality. Returns the outcome in words.
std::string finish(VolumeMesh& mesh, const MeshingSettings& s) {
  mesh.surface_offset_mm = 1e3 * restore_volume(mesh.nodes_m, mesh.tetrahedra, mesh.segmented_volume_m3,
                                                0.1e-3 * s.element_size_mm, s.min_dihedral_deg);
  const auto repair_started = std::chrono::steady_clock::now();
  mesh.repair = repair_slivers(mesh.nodes_m, mesh.tetrahedra, std::max(12.0, s.min_dihedral_deg + 2));
  mesh.boundary = boundary_faces(mesh.tetrahedra, &mesh.closed_manifold);
  mesh.quality = mesh_quality(mesh.nodes_m, mesh.tetrahedra);
  mesh.volume_m3 = mesh.quality.volume_m3;
  mesh.optimisation_seconds += seconds_since(repair_started);
  char text[200];
  std::snprintf(text, sizeof text, "%zu tetrahedra, smallest dihedral %.1f deg%s%s", mesh.tetrahedra.size(),
                mesh.quality.min_dihedral_deg, mesh.closed_manifold ? "" : ", boundary NOT closed and manifold",
                mesh.quality.inverted + mesh.quality.degenerate > 0 ? ", inverted or degenerate elements" : "");
  return text;
}

}  // namespace


namespace {

// The surface remeshed, then as it is; each with Delaunay, then HXT.
std::vector<FillPath> surface_then_given() {
  std::vector<FillPath> paths = fill_paths(FillSurface::remeshed);
  for (const FillPath& p : fill_paths(FillSurface::as_given)) paths.push_back(p);
  return paths;
}

// Orients, checks (and where it can, repairs) a triangle surface in millimetres, and fills it with
// tetrahedra (metres).
VolumeMesh fill_surface(vtkSmartPointer<vtkPolyData> surface, const MeshingSettings& s, VolumeMesh out,
                        const std::vector<FillPath>& paths, const std::string& surface_name) {
  auto triangles = vtkSmartPointer<vtkTriangleFilter>::New();
  triangles->SetInputData(surface);
  auto tidy = vtkSmartPointer<vtkCleanPolyData>::New();
  tidy->SetInputConnection(triangles->GetOutputPort());
  auto oriented = vtkSmartPointer<vtkPolyDataNormals>::New();
  oriented->SetInputConnection(tidy->GetOutputPort());
  oriented->ConsistencyOn();
  oriented->AutoOrientNormalsOn();
  oriented->SplittingOff();
  oriented->Update();
  surface = oriented->GetOutput();
  if (open_edges(surface) > 0) {
    auto fill = vtkSmartPointer<vtkFillHolesFilter>::New();
    fill->SetInputData(surface);
    fill->SetHoleSize(1e9);
    fill->Update();
    surface = fill->GetOutput();
    const long left = open_edges(surface);
    if (left > 0)
      throw std::runtime_error("meshing: the surface has " + std::to_string(left) +
                               " boundary or non-manifold edges that could not be repaired");
  }
  if (out.segmented_volume_m3 == 0) {  // a surface given as such: its own volume is the reference
    auto mass = vtkSmartPointer<vtkMassProperties>::New();
    mass->SetInputData(surface);
    mass->Update();
    out.segmented_volume_m3 = mass->GetVolume() * 1e-9;
    check_settings(mass->GetVolume(), s);
  }
  out.closed_manifold = true;
  out.surface_triangles = surface->GetNumberOfPolys();

  // 3. Gmsh fills the surface with tetrahedra, along the first path that gives a valid mesh (no
  // element inverted or degenerate, the boundary closed and manifold) whose smallest dihedral angle,
  // after the sliver repair, reaches the bound; the best valid mesh otherwise (the caller refuses it).
  report(s, "volume meshing", 0.3);
  std::vector<double> nodes_mm(3 * std::size_t(surface->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i) surface->GetPoint(i, &nodes_mm[3 * std::size_t(i)]);
  std::vector<std::size_t> corners;
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < surface->GetNumberOfCells(); ++c) {
    surface->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < 3; ++k) corners.push_back(std::size_t(ids->GetId(k)));
  }
  const VolumeMesh base = out;
  bool have = false;
  std::string failures;
  for (std::size_t k = 0; k < std::size(paths); ++k) {
    const FillPath path = paths[k];
    const auto path_started = std::chrono::steady_clock::now();
    VolumeMesh mesh = base;
    std::string outcome;
    try {
      GmshFill fill = gmsh_fill(nodes_mm, corners, s, path);
      mesh.nodes_m = std::move(fill.nodes_m), mesh.tetrahedra = std::move(fill.tetrahedra);
      mesh.surface_remeshed = fill.surface_remeshed;
      mesh.optimisation_seconds = fill.optimisation_seconds;
      report(s, "sliver repair", 0.3 + 0.6 * (k + 0.8) / std::size(paths));
      outcome = finish(mesh, s);
    } catch (const std::exception& e) {
      outcome = std::string("failed: ") + e.what();
      failures += (failures.empty() ? "" : "; ") + surface_name + describe(path) + ": " + e.what();
    }
    char timing[40];
    std::snprintf(timing, sizeof timing, " (%.1f s)", seconds_since(path_started));
    out.attempts.push_back(surface_name + describe(path) + ": " + outcome + timing);
    const bool valid = !mesh.tetrahedra.empty() && mesh.closed_manifold && mesh.quality.inverted == 0 && mesh.quality.degenerate == 0;
    if (valid && (!have || mesh.quality.min_dihedral_deg > out.quality.min_dihedral_deg)) {
      mesh.attempts = std::move(out.attempts);
      out = std::move(mesh);
      out.path = surface_name + describe(path);
      have = true;
    }
    if (have && meets(out.quality, s)) break;
    report(s, "volume meshing", 0.3 + 0.6 * (k + 1.0) / std::size(paths));
  }
  if (!have) throw std::runtime_error("no path gave a valid mesh (" + failures + ")");
  out.quality_met = meets(out.quality, s);
  return out;
}

// The surface of the mask, in millimetres and in space; `smoother`: blurred twice as much, on a
// grid of half the element size (features below the element size smoothed away).
vtkSmartPointer<vtkPolyData> mask_surface(const MaskVolume& mask, const MeshingSettings& s, bool smoother, VolumeMesh& out) {
  // 1. The mask, blurred and contoured at 0.5 on a grid of about a third of the element size (at
  // most the voxels'): the surface comes with triangles near the element size and without features
  // far below it, so the clean-up has little to decimate (decimating a million triangles was most of
  // the time on a head MRI, and its folds made surfaces that intersect themselves). Padded with empty
  // voxels so that the surface closes at the volume's faces.
  report(s, "surface extraction", 0.0);
  const double grid_mm = s.element_size_mm / (smoother ? 2 : 3);
  std::array<double, 3> sigma{}, magnify{};  // resampled where an axis's magnify is under 1
  for (int d = 0; d < 3; ++d) {
    magnify[d] = grid_mm > 1.2 * mask.spacing_mm[d] ? mask.spacing_mm[d] / grid_mm : 1.0;
    sigma[d] = std::max(0.7, 0.5 / magnify[d]) * (smoother ? 2 : 1);  // voxels: half the new grid's spacing
  }
  const int pad = 2 + static_cast<int>(std::ceil(2 * std::max({sigma[0], sigma[1], sigma[2]})));
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(mask.dimensions[0] + 2 * pad, mask.dimensions[1] + 2 * pad, mask.dimensions[2] + 2 * pad);
  image->SetSpacing(mask.spacing_mm.data());
  image->SetOrigin(mask.origin_mm[0] - pad * mask.spacing_mm[0], mask.origin_mm[1] - pad * mask.spacing_mm[1],
                   mask.origin_mm[2] - pad * mask.spacing_mm[2]);
  auto values = vtkSmartPointer<vtkFloatArray>::New();
  values->SetNumberOfTuples(vtkIdType(image->GetNumberOfPoints()));
  values->Fill(0);
  for (int k = 0; k < mask.dimensions[2]; ++k)
    for (int j = 0; j < mask.dimensions[1]; ++j)
      for (int i = 0; i < mask.dimensions[0]; ++i)
        if (mask.data[(std::size_t(k) * mask.dimensions[1] + j) * mask.dimensions[0] + i])
          values->SetValue(image->ComputePointId(std::array<int, 3>{i + pad, j + pad, k + pad}.data()), 1.0f);
  image->GetPointData()->SetScalars(values);
  vtkSmartPointer<vtkPolyData> extracted = blurred_level_set(image, sigma, magnify, /*largest_only=*/true);
  if (extracted->GetNumberOfPolys() == 0) {
    char text[300];
    std::snprintf(text, sizeof text,
                  "meshing: nothing is left of the segmentation (%.4g ml) once smoothed at the element size: no part of "
                  "it is thicker than about %.2g mm (a smaller --size keeps thinner parts)",
                  out.segmented_volume_m3 * 1e6, 2 * grid_mm);
    throw std::runtime_error(text);
  }

  // 2. Smoothing that does not shrink, decimation towards the element size.
  report(s, "surface clean-up", 0.15);
  vtkSmartPointer<vtkPolyData> surface = smoothed_surface(extracted, s.smoothing_iterations);
  if (!smoother) {  // the smoother surface is already on a grid near the element size
    // Decimation folds the surface here and there; smoothing again unfolds it (else Gmsh cannot
    // parametrise the spine's surface, and the folds make slivers).
    vtkSmartPointer<vtkPolyData> decimated = decimated_towards(surface, s.element_size_mm, 200);
    // Quadric decimation does not keep the topology: on a folded surface (a brain's gyri) it
    // pinches edges into non-manifold ones. Then the surface stays as extracted (Gmsh remeshes it).
    if (decimated != surface && open_edges(decimated) == 0) surface = decimated;
  }
  // Into space: the image's index axes along its direction cosines, about its origin.
  if (mask.direction != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}) {
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i) {
      double p[3], q[3];
      surface->GetPoint(i, p);
      for (int r = 0; r < 3; ++r) {
        q[r] = mask.origin_mm[r];
        for (int c = 0; c < 3; ++c) q[r] += mask.direction[3 * r + c] * (p[c] - mask.origin_mm[c]);
      }
      points->InsertNextPoint(q);
    }
    auto placed = vtkSmartPointer<vtkPolyData>::New();
    placed->DeepCopy(surface);
    placed->SetPoints(points);
    surface = placed;
  }
  return surface;
}

// The segmentation's restricted Delaunay surface (meshes/restricted_surface.h), its largest piece:
// a volume bounded by several shells would take all but one for holes.
vtkSmartPointer<vtkPolyData> restricted_delaunay_surface(const MaskVolume& mask, const MeshingSettings& s, int* pieces) {
  // A triangle may stray from the level by half a voxel: the volume is then within about half a
  // voxel times the area of the segmentation's (restore_volume's offset closes it), and the surface
  // follows any feature thicker than a voxel or two.
  const double voxel = std::min({mask.spacing_mm[0], mask.spacing_mm[1], mask.spacing_mm[2]});
  const RestrictedSurface restricted = restricted_surface(mask, s, 0.5 * voxel);
  *pieces = restricted.pieces;
  auto largest = vtkSmartPointer<vtkPolyDataConnectivityFilter>::New();
  largest->SetInputData(triangle_surface(restricted.nodes_mm, restricted.triangles));
  largest->SetExtractionModeToLargestRegion();
  auto clean = vtkSmartPointer<vtkCleanPolyData>::New();
  clean->SetInputConnection(largest->GetOutputPort());
  clean->Update();
  return clean->GetOutput();
}

}  // namespace

VolumeMesh mesh_mask(const MaskVolume& mask, const MeshingSettings& s) {
  VolumeMesh out;
  long voxels = 0;
  for (auto v : mask.data) voxels += v != 0;
  if (voxels == 0) throw std::runtime_error("meshing: the segmentation is empty (no voxel set)");
  const double voxel_mm3 = mask.spacing_mm[0] * mask.spacing_mm[1] * mask.spacing_mm[2];
  out.segmented_volume_m3 = voxels * voxel_mm3 * 1e-9;
  check_settings(voxels * voxel_mm3, s);
  // Elements four times thicker than the whole segmentation cannot represent it, however the surface
  // is made (a sheet one voxel thick at 8 mm): refused with its thickness.
  if (const double thickest = thickest_part_mm(mask); thickest < s.element_size_mm / 4) {
    char text[300];
    std::snprintf(text, sizeof text,
                  "meshing: the segmentation is nowhere thicker than %.2g mm, too thin for elements of %.3g mm (at "
                  "least a quarter of the element size is needed): use --size %.2g or less",
                  thickest, s.element_size_mm, 4 * thickest);
    throw std::runtime_error(text);
  }
  // The surface as extracted, remeshed by Gmsh or kept; if neither gives the quality asked, a
  // smoother surface (what was in the way is most often a feature thinner than the elements: two
  // sides of an ear or a fold whose triangles cross once remeshed at the element size).
  double surface_seconds = 0, fill_seconds = 0;
  std::vector<std::string> attempts;
  VolumeMesh best;
  bool have = false;
  std::string failures;
  // Which of two meshes to keep: one that meets the quality asked over one that does not, then the
  // larger smallest dihedral angle (a mesh of 12.4 degrees whose radius ratio misses the bound must
  // not displace one of 12.1 degrees that meets both).
  const auto better = [](const VolumeMesh& a, const VolumeMesh& b) {
    if (a.quality_met != b.quality_met) return a.quality_met;
    return a.quality.min_dihedral_deg > b.quality.min_dihedral_deg;
  };
  // The mesh kept, with every try and each phase's time.
  const auto done = [&] {
    best.attempts = attempts;
    best.phases = {{"surface", surface_seconds},
                   {"volume mesh", fill_seconds - best.optimisation_seconds},
                   {"optimisation", best.optimisation_seconds}};
    report(s, "done", 1.0);
    return std::move(best);
  };
  // First CGAL's restricted Delaunay surface filled by Gmsh (Delaunay, then HXT): closed, manifold
  // and without crossing triangles by construction; if the sliver repair cannot bring that mesh to
  // the angle asked, the same with smaller triangles (another Delaunay mesh: on a brain at 8 mm the worst element varied
  // from 7.9 to 12.1 degrees between runs, one sliver inside the mesh, none on its surface). Then the surfaces contoured by VTK (as extracted,
  // remeshed by Gmsh or kept; then smoother).
  for (const double finer : {1.0, 0.85, 0.7}) {
    if (!s.restricted_surface) break;
    auto phase = std::chrono::steady_clock::now();
    char name[60] = "";
    if (finer < 1) std::snprintf(name, sizeof name, "triangles %.2g x size, ", finer);
    try {
      int pieces = 0;
      MeshingSettings at = s;
      at.element_size_mm = finer * s.element_size_mm, at.refine_size_mm = finer * s.refine_size_mm;
      vtkSmartPointer<vtkPolyData> surface;
      try {
        surface = restricted_delaunay_surface(mask, at, &pieces);
      } catch (const std::exception& e) {  // no surface: a finer one would not have one either
        failures = e.what();
        attempts.push_back(describe(FillSurface::restricted) + std::string(": failed: ") + e.what());
        break;
      }
      surface_seconds += seconds_since(phase);
      phase = std::chrono::steady_clock::now();
      VolumeMesh mesh = fill_surface(surface, s, out, fill_paths(FillSurface::restricted), name);
      if (pieces > 1)
        mesh.attempts.back() += " (the blurred segmentation fell into " + std::to_string(pieces) + " pieces; the largest meshed)";
      attempts.insert(attempts.end(), mesh.attempts.begin(), mesh.attempts.end());
      if (!have || better(mesh, best)) best = std::move(mesh), have = true;
    } catch (const std::exception& e) {
      failures += (failures.empty() ? "" : "; ") + std::string(name) + e.what();
      attempts.push_back(name + std::string(describe(FillSurface::restricted)) + ": failed: " + e.what());
    }
    fill_seconds += seconds_since(phase);
    if (have && best.quality_met) return done();
  }
  for (const bool smoother : {false, true}) {
    auto phase = std::chrono::steady_clock::now();
    vtkSmartPointer<vtkPolyData> surface;
    try {
      surface = mask_surface(mask, s, smoother, out);
    } catch (const std::exception& e) {
      if (!smoother && !have) throw std::runtime_error(failures.empty() ? e.what() : failures + "; " + e.what());
      failures += std::string("; smoother surface: ") + e.what();
      attempts.push_back(std::string("smoother surface: ") + e.what());
      break;
    }
    surface_seconds += seconds_since(phase);
    phase = std::chrono::steady_clock::now();
    try {
      VolumeMesh mesh = fill_surface(surface, s, out,
                                     smoother ? fill_paths(FillSurface::remeshed) : surface_then_given(),
                                     smoother ? "smoother surface, " : "");
      attempts.insert(attempts.end(), mesh.attempts.begin(), mesh.attempts.end());
      if (!have || better(mesh, best)) best = std::move(mesh), have = true;
    } catch (const std::exception& e) {
      failures += (failures.empty() ? "" : "; ") + std::string(e.what());
      attempts.push_back(std::string(smoother ? "smoother surface: " : "surface: ") + e.what());
    }
    fill_seconds += seconds_since(phase);
    if (have && best.quality_met) break;
  }
  if (!have) throw std::runtime_error("meshing: " + failures);
  return done();
}

VolumeMesh mesh_triangle_surface(const std::vector<Point3>& nodes_mm, const std::vector<Triangle>& triangles,
                                 const MeshingSettings& s) {
  for (const auto& t : triangles)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(nodes_mm.size()))
        throw std::runtime_error("meshing: a triangle refers to node " + std::to_string(v) + " of " +
                                 std::to_string(nodes_mm.size()));
  if (triangles.empty()) throw std::runtime_error("meshing: the surface has no triangle");
  VolumeMesh mesh = fill_surface(triangle_surface(nodes_mm, triangles), s, VolumeMesh{}, surface_then_given(), "");
  report(s, "done", 1.0);
  return mesh;
}

}  // namespace fetouch::meshes
