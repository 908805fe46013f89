#include "meshes/volume_mesher.h"

#include "meshes/tet_repair.h"

#include <gmsh.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCleanPolyData.h>
#include <vtkFeatureEdges.h>
#include <vtkFillHolesFilter.h>
#include <vtkFlyingEdges3D.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkImageGaussianSmooth.h>
#include <vtkIntArray.h>
#include <vtkMassProperties.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkPolyDataNormals.h>
#include <vtkQuadricDecimation.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkFieldData.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWindowedSincPolyDataFilter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <map>
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

// Windowed-sinc smoothing: a low-pass filter on the surface that, unlike Laplacian smoothing,
// does not shrink it.
vtkSmartPointer<vtkPolyData> smoothed(vtkPolyData* surface, int iterations) {
  auto smooth = vtkSmartPointer<vtkWindowedSincPolyDataFilter>::New();
  smooth->SetInputData(surface);
  smooth->SetNumberOfIterations(iterations);
  smooth->SetPassBand(0.1);
  smooth->BoundarySmoothingOff();
  smooth->FeatureEdgeSmoothingOff();
  smooth->NonManifoldSmoothingOn();
  smooth->NormalizeCoordinatesOn();
  smooth->Update();
  return smooth->GetOutput();
}

// Each interface face's group, an index into interface_groups(mesh).
std::vector<int> interface_ids(const VolumeMesh& mesh) {
  std::map<std::array<int, 2>, int> index;
  for (const auto& pair : mesh.interface_regions) index.emplace(pair, 0);
  int next = 0;
  for (auto& [pair, id] : index) id = next++;
  std::vector<int> ids;
  for (const auto& pair : mesh.interface_regions) ids.push_back(index[pair]);
  return ids;
}

void report(const MeshingSettings& s, const std::string& step, double done) {
  if (s.progress) s.progress(step, done);
}

// A Gmsh session for one call (Gmsh is global state).
struct GmshSession {
  GmshSession() {
    gmsh::initialize();
    gmsh::option::setNumber("General.Terminal", std::getenv("FETOUCH_GMSH_LOG") ? 1 : 0);
    gmsh::option::setNumber("General.Verbosity", 1);
    // One thread: HXT in parallel gives a different mesh from run to run.
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads1D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads2D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads3D", 1);
  }
  ~GmshSession() { gmsh::finalize(); }
};

// Refuses settings that make no sense or a mesh too large for the memory, from the volume to fill.
void check_settings(double volume_mm3, const MeshingSettings& s) {
  if (!(s.element_size_mm > 0)) throw std::runtime_error("meshing: the element size must be positive");
  if (s.refine_radius_mm > 0 && !(s.refine_size_mm > 0))
    throw std::runtime_error("meshing: the refinement size must be positive");
  // A regular tetrahedron of edge a has a volume of a^3 / (6 sqrt 2).
  const auto tetrahedra_in = [](double v, double size_mm) { return v / (std::pow(size_mm, 3) / (6 * std::sqrt(2.0))); };
  double estimate = tetrahedra_in(volume_mm3, s.element_size_mm);
  if (s.refine_radius_mm > 0) estimate += tetrahedra_in(4 * M_PI / 3 * std::pow(2 * s.refine_radius_mm, 3), s.refine_size_mm);
  if (estimate > 2e7)
    throw std::runtime_error("meshing: an element size of " + std::to_string(s.element_size_mm) + " mm" +
                             (s.refine_radius_mm > 0 ? " (" + std::to_string(s.refine_size_mm) + " mm refined)" : "") +
                             " would make about " + std::to_string(static_cast<long>(estimate)) +
                             " tetrahedra, more than memory allows (20 million)");
}

}  // namespace


namespace {

// Orients, checks (and where it can, repairs) a triangle surface in millimetres, and fills it with
// tetrahedra (metres).
VolumeMesh fill_surface(vtkSmartPointer<vtkPolyData> surface, const MeshingSettings& s, VolumeMesh out) {
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

  // 3. Gmsh fills the surface with tetrahedra.
  report(s, "volume meshing", 0.3);
  GmshSession session;
  std::vector<std::size_t> node_tags(surface->GetNumberOfPoints());
  std::vector<double> coordinates;
  coordinates.reserve(3 * node_tags.size());
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i) {
    double x[3];
    surface->GetPoint(i, x);
    node_tags[i] = std::size_t(i) + 1;
    for (double c : x) coordinates.push_back(c * 1e-3);  // mm -> m
  }
  std::vector<std::size_t> triangle_nodes;
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < surface->GetNumberOfCells(); ++c) {
    surface->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < 3; ++k) triangle_nodes.push_back(std::size_t(ids->GetId(k)) + 1);
  }
  const auto add_surface = [&] {
    gmsh::model::add("tissue");
    gmsh::model::addDiscreteEntity(2, 1);
    gmsh::model::mesh::addNodes(2, 1, node_tags, coordinates);
    gmsh::model::mesh::addElementsByType(1, 2, {}, triangle_nodes);
  };
  // The surface is split into patches Gmsh can parametrise and remesh at the target size (the
  // decimated triangles are too uneven for good tetrahedra next to them). No feature angle: the
  // tissue's surface is smooth, and feature curves kept the decimation's folds as creases. A
  // surface Gmsh cannot parametrise is kept as it is.
  std::vector<int> patch_tags{1};
  try {
    add_surface();
    gmsh::model::mesh::classifySurfaces(M_PI, true, true, M_PI);
    gmsh::model::mesh::createGeometry();
    std::vector<std::pair<int, int>> patches;
    gmsh::model::getEntities(patches, 2);
    patch_tags.clear();
    for (const auto& [dim, tag] : patches) patch_tags.push_back(tag);
    out.surface_remeshed = true;
  } catch (const std::string&) {
    gmsh::model::remove();
    add_surface();
  }
  try {
    const int loop = gmsh::model::geo::addSurfaceLoop(patch_tags);
    gmsh::model::geo::addVolume({loop}, 1);
    gmsh::model::geo::synchronize();
  } catch (const std::string& e) {
    throw std::runtime_error("meshing: Gmsh could not bound a volume by the surface: " + e);
  }
  const double h = s.element_size_mm * 1e-3;
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.2 * (s.refine_radius_mm > 0 ? std::min(h, s.refine_size_mm * 1e-3) : h));
  if (s.refine_radius_mm > 0) {
    // Finer elements in a ball (where the probe touches), grading to the element size over one
    // more radius.
    const int ball = gmsh::model::mesh::field::add("Ball");
    gmsh::model::mesh::field::setNumber(ball, "Radius", s.refine_radius_mm * 1e-3);
    gmsh::model::mesh::field::setNumber(ball, "Thickness", s.refine_radius_mm * 1e-3);
    gmsh::model::mesh::field::setNumber(ball, "VIn", s.refine_size_mm * 1e-3);
    gmsh::model::mesh::field::setNumber(ball, "VOut", h);
    gmsh::model::mesh::field::setNumber(ball, "XCenter", s.refine_center_mm[0] * 1e-3);
    gmsh::model::mesh::field::setNumber(ball, "YCenter", s.refine_center_mm[1] * 1e-3);
    gmsh::model::mesh::field::setNumber(ball, "ZCenter", s.refine_center_mm[2] * 1e-3);
    gmsh::model::mesh::field::setAsBackgroundMesh(ball);
  }
  gmsh::option::setNumber("Mesh.Optimize", 1);
  // HXT, then the optimiser on every element of quality (gamma) under 0.5: on the phantom's fetus
  // the plain Delaunay mesher left slivers of 1.3 degrees, HXT with the default threshold 9.3.
  gmsh::option::setNumber("Mesh.Algorithm3D", 10);
  gmsh::option::setNumber("Mesh.OptimizeThreshold", 0.5);
  try {
    gmsh::model::mesh::generate(3);
    report(s, "quality optimisation", 0.8);
    // Debian's Gmsh has no Netgen: its own optimiser, then node relocation.
    gmsh::model::mesh::optimize("", false, 2);
    gmsh::model::mesh::optimize("Relocate3D");
  } catch (const std::string& e) {  // Gmsh's API throws its message as a string
    throw std::runtime_error("meshing: Gmsh could not fill the surface: " + e);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("meshing: Gmsh could not fill the surface: ") + e.what());
  }
  try {
    std::vector<std::size_t> mesh_tags, element_tags, element_nodes;  // Gmsh takes non-empty vectors as preallocated
    std::vector<double> all_coordinates, parametric;
    gmsh::model::mesh::getNodes(mesh_tags, all_coordinates, parametric, -1, -1, false, false);
    std::map<std::size_t, int> index;
    for (std::size_t i = 0; i < mesh_tags.size(); ++i) {
      index[mesh_tags[i]] = static_cast<int>(i);
      out.nodes_m.push_back({all_coordinates[3 * i], all_coordinates[3 * i + 1], all_coordinates[3 * i + 2]});
    }
    gmsh::model::mesh::getElementsByType(4, element_tags, element_nodes, -1);
    if (element_nodes.empty()) throw std::runtime_error("meshing: Gmsh made no tetrahedra");
    for (std::size_t e = 0; e < element_nodes.size(); e += 4) {
      Tet t{index.at(element_nodes[e]), index.at(element_nodes[e + 1]), index.at(element_nodes[e + 2]),
            index.at(element_nodes[e + 3])};
      if (tet_signed_volume(out.nodes_m[t[0]], out.nodes_m[t[1]], out.nodes_m[t[2]], out.nodes_m[t[3]]) < 0)
        std::swap(t[2], t[3]);
      out.tetrahedra.push_back(t);
    }
  } catch (const std::string& e) {
    throw std::runtime_error("meshing: Gmsh: " + e);
  }
  // Slivers the optimiser left (against the surface, whose nodes it keeps): peeled, flipped away
  // or relocated (meshes/tet_repair.h), then the boundary as the elements now have it.
  report(s, "sliver repair", 0.9);
  out.repair = repair_slivers(out.nodes_m, out.tetrahedra, 12);
  out.boundary = boundary_faces(out.tetrahedra);
  out.closed_manifold = boundary_is_closed_manifold(out.tetrahedra);
  out.quality = mesh_quality(out.nodes_m, out.tetrahedra);
  out.volume_m3 = out.quality.volume_m3;
  report(s, "done", 1.0);
  return out;
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

  // 1. The mask, padded by two empty voxels (so that the surface closes at the volume's faces).
  report(s, "surface extraction", 0.0);
  const int pad = 2;
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
  auto blur = vtkSmartPointer<vtkImageGaussianSmooth>::New();
  blur->SetInputData(image);
  blur->SetStandardDeviations(0.7, 0.7, 0.7);
  blur->SetRadiusFactors(2, 2, 2);
  auto contour = vtkSmartPointer<vtkFlyingEdges3D>::New();
  contour->SetInputConnection(blur->GetOutputPort());
  contour->SetValue(0, 0.5);
  contour->ComputeNormalsOff();
  contour->ComputeGradientsOff();
  contour->ComputeScalarsOff();
  auto largest = vtkSmartPointer<vtkPolyDataConnectivityFilter>::New();
  largest->SetInputConnection(contour->GetOutputPort());
  largest->SetExtractionModeToLargestRegion();
  auto clean = vtkSmartPointer<vtkCleanPolyData>::New();
  clean->SetInputConnection(largest->GetOutputPort());
  clean->Update();
  if (clean->GetOutput()->GetNumberOfPolys() == 0) throw std::runtime_error("meshing: the segmentation has no surface");

  // 2. Smoothing that does not shrink, decimation towards the element size.
  report(s, "surface clean-up", 0.15);
  vtkSmartPointer<vtkPolyData> surface = smoothed(clean->GetOutput(), s.smoothing_iterations);
  auto mass = vtkSmartPointer<vtkMassProperties>::New();
  mass->SetInputData(surface);
  mass->Update();
  const double triangle_area = std::sqrt(3.0) / 4 * s.element_size_mm * s.element_size_mm;
  const double wanted = std::max(200.0, mass->GetSurfaceArea() / triangle_area);
  const double have = surface->GetNumberOfPolys();
  if (wanted < have) {
    auto decimate = vtkSmartPointer<vtkQuadricDecimation>::New();
    decimate->SetInputData(surface);
    decimate->SetTargetReduction(1 - wanted / have);
    decimate->VolumePreservationOn();
    decimate->Update();
    surface = decimate->GetOutput();
    // Decimation folds the surface here and there; smoothing again unfolds it (else Gmsh cannot
    // parametrise the spine's surface, and the folds make slivers).
    surface = smoothed(decimate->GetOutput(), 10);
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
  return fill_surface(surface, s, out);
}

VolumeMesh mesh_triangle_surface(const std::vector<Point3>& nodes_mm, const std::vector<Triangle>& triangles,
                                 const MeshingSettings& s) {
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  for (const auto& p : nodes_mm) points->InsertNextPoint(p.data());
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& t : triangles) {
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(nodes_mm.size()))
        throw std::runtime_error("meshing: a triangle refers to node " + std::to_string(v) + " of " +
                                 std::to_string(nodes_mm.size()));
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    cells->InsertNextCell(3, ids);
  }
  surface->SetPoints(points);
  surface->SetPolys(cells);
  if (triangles.empty()) throw std::runtime_error("meshing: the surface has no triangle");
  return fill_surface(surface, s, VolumeMesh{});
}

void write_volume_mesh(const VolumeMesh& mesh, const std::filesystem::path& path, int partitions) {
  const std::string name = path.string();
  const std::string e = path.extension().string();
  if (e == ".vtu") {
    auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    for (const auto& p : mesh.nodes_m) points->InsertNextPoint(p.data());
    grid->SetPoints(points);
    auto boundary = vtkSmartPointer<vtkIntArray>::New();
    boundary->SetName("boundary_id");
    auto material = vtkSmartPointer<vtkIntArray>::New();
    material->SetName("material_id");
    // Regions: material id r + 1 (as the .msh's volume groups), boundary id r (NAME_outer).
    const bool regions = !mesh.region_names.empty();
    for (std::size_t k = 0; k < mesh.tetrahedra.size(); ++k) {
      const auto& t = mesh.tetrahedra[k];
      const vtkIdType v[4] = {t[0], t[1], t[2], t[3]};
      grid->InsertNextCell(VTK_TETRA, 4, v);
      boundary->InsertNextValue(-1), material->InsertNextValue(regions ? mesh.region[k] + 1 : 0);
    }
    for (std::size_t k = 0; k < mesh.boundary.size(); ++k) {
      const auto& t = mesh.boundary[k];
      const vtkIdType v[3] = {t[0], t[1], t[2]};
      grid->InsertNextCell(VTK_TRIANGLE, 3, v);
      boundary->InsertNextValue(regions ? mesh.boundary_region[k] : 0), material->InsertNextValue(-1);
    }
    // Interfaces: boundary ids after the outer surfaces', in interface_groups' order (inner faces:
    // the solver reads them as names only).
    const auto interfaces = interface_ids(mesh);
    for (std::size_t k = 0; k < mesh.interfaces.size(); ++k) {
      const auto& t = mesh.interfaces[k];
      const vtkIdType v[3] = {t[0], t[1], t[2]};
      grid->InsertNextCell(VTK_TRIANGLE, 3, v);
      boundary->InsertNextValue(static_cast<int>(mesh.region_names.size()) + interfaces[k]), material->InsertNextValue(-1);
    }
    grid->GetCellData()->AddArray(boundary);
    grid->GetCellData()->AddArray(material);
    auto names = vtkSmartPointer<vtkStringArray>::New();
    names->SetName("boundary_names");
    if (!regions) names->InsertNextValue("surface");
    for (const auto& region : mesh.region_names) names->InsertNextValue(region + "_outer");
    for (const auto& [name, faces] : interface_groups(mesh)) names->InsertNextValue(name);
    grid->GetFieldData()->AddArray(names);
    if (regions) {  // entry i names material id i (0 unused)
      auto region_names = vtkSmartPointer<vtkStringArray>::New();
      region_names->SetName("region_names");
      region_names->InsertNextValue("");
      for (const auto& region : mesh.region_names) region_names->InsertNextValue(region);
      grid->GetFieldData()->AddArray(region_names);
    }
    auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
    writer->SetFileName(name.c_str());
    writer->SetInputData(grid);
    if (!writer->Write()) throw std::runtime_error(name + ": could not be written");
    return;
  }
  if (e != ".msh") throw std::runtime_error(name + ": meshes are written as .msh or .vtu");
  GmshSession session;
  gmsh::model::add("tissue");
  // One discrete volume per region (tag r + 1) and its outer surface (tag r + 1); one of each, named
  // `tissue` and `surface`, without regions.
  const bool regions = !mesh.region_names.empty();
  const int n = regions ? static_cast<int>(mesh.region_names.size()) : 1;
  for (int r = 1; r <= n; ++r) {
    gmsh::model::addDiscreteEntity(2, r);
    gmsh::model::addDiscreteEntity(3, r, {r});
  }
  std::vector<std::size_t> tags(mesh.nodes_m.size());
  std::vector<double> xyz;
  for (std::size_t i = 0; i < tags.size(); ++i) {
    tags[i] = i + 1;
    xyz.insert(xyz.end(), mesh.nodes_m[i].begin(), mesh.nodes_m[i].end());
  }
  gmsh::model::mesh::addNodes(3, 1, tags, xyz);
  std::vector<std::vector<std::size_t>> tri(static_cast<std::size_t>(n)), tet(static_cast<std::size_t>(n));
  for (std::size_t k = 0; k < mesh.boundary.size(); ++k)
    for (int v : mesh.boundary[k]) tri[regions ? std::size_t(mesh.boundary_region[k]) : 0].push_back(std::size_t(v) + 1);
  for (std::size_t k = 0; k < mesh.tetrahedra.size(); ++k)
    for (int v : mesh.tetrahedra[k]) tet[regions ? std::size_t(mesh.region[k]) : 0].push_back(std::size_t(v) + 1);
  for (int r = 1; r <= n; ++r) {
    gmsh::model::mesh::addElementsByType(r, 2, {}, tri[std::size_t(r - 1)]);
    gmsh::model::mesh::addElementsByType(r, 4, {}, tet[std::size_t(r - 1)]);
    const std::string group = regions ? mesh.region_names[std::size_t(r - 1)] : "tissue";
    // Volume groups 1..n are the regions (material ids); surface groups 1..n their outer surfaces.
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {r}, regions ? r : 1), regions ? group + "_outer" : "surface");
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {r}, regions ? r : 2), group);
  }
  // Interfaces: one discrete surface and group each, tags n + 1, n + 2, ... (bounding no volume).
  if (regions) {
    const auto groups = interface_groups(mesh);
    const auto ids = interface_ids(mesh);
    std::vector<std::vector<std::size_t>> faces(groups.size());
    for (std::size_t k = 0; k < mesh.interfaces.size(); ++k)
      for (int v : mesh.interfaces[k]) faces[std::size_t(ids[k])].push_back(std::size_t(v) + 1);
    for (std::size_t g = 0; g < groups.size(); ++g) {
      const int tag = n + 1 + static_cast<int>(g);
      gmsh::model::addDiscreteEntity(2, tag);
      gmsh::model::mesh::addElementsByType(tag, 2, {}, faces[g]);
      gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {tag}, tag), groups[g].first);
    }
  }
  if (partitions > 1) gmsh::model::mesh::partition(partitions);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  try {
    gmsh::write(name);
  } catch (const std::exception&) {
    throw std::runtime_error(name + ": could not be written");
  }
  if (!std::filesystem::exists(path)) throw std::runtime_error(name + ": could not be written");
}

}  // namespace fetouch::meshes
