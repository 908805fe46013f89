#include "meshes/volume_mesher.h"

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
#include <stdexcept>

namespace fetouch::meshes {

namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

// The signed volume of a tetrahedron: positive when (1 - 0, 2 - 0, 3 - 0) is right-handed.
double signed_volume(const std::vector<Vec>& nodes, const std::array<int, 4>& t) {
  const Vec& o = nodes[t[0]];
  return dot(sub(nodes[t[1]], o), cross(sub(nodes[t[2]], o), sub(nodes[t[3]], o))) / 6;
}

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

}  // namespace

QualityReport mesh_quality(const std::vector<std::array<double, 3>>& nodes, const std::vector<std::array<int, 4>>& tets) {
  QualityReport q;
  q.min_dihedral_deg = 180, q.max_dihedral_deg = 0, q.min_radius_ratio = 1;
  static const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};  // face opposite vertex f
  for (const auto& t : tets) {
    const Vec p[4] = {nodes[t[0]], nodes[t[1]], nodes[t[2]], nodes[t[3]]};
    const double volume = signed_volume(nodes, t);
    q.volume_m3 += volume;
    double scale = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) scale = std::max(scale, norm(sub(p[a], p[b])));
    if (volume <= 0) {
      ++(std::abs(volume) <= 1e-12 * scale * scale * scale ? q.degenerate : q.inverted);
      q.min_dihedral_deg = 0, q.min_radius_ratio = 0;
      continue;
    }
    // Outward face normals; the dihedral angle at the edge shared by faces f and g is pi minus the
    // angle between their normals.
    Vec n[4];
    double area = 0;
    for (int f = 0; f < 4; ++f) {
      n[f] = cross(sub(p[faces[f][1]], p[faces[f][0]]), sub(p[faces[f][2]], p[faces[f][0]]));
      area += norm(n[f]) / 2;
      const double length = norm(n[f]);
      for (double& c : n[f]) c /= length;
    }
    for (int f = 0; f < 4; ++f)
      for (int g = f + 1; g < 4; ++g) {
        const double angle = 180 - std::acos(std::clamp(dot(n[f], n[g]), -1.0, 1.0)) * 180 / M_PI;
        q.min_dihedral_deg = std::min(q.min_dihedral_deg, angle);
        q.max_dihedral_deg = std::max(q.max_dihedral_deg, angle);
        ++q.dihedral_histogram[std::min(17, static_cast<int>(angle / 10))];
      }
    // Radius ratio 3 r / R: r = 3V / area; R from the products of opposite edges' lengths.
    const double a = norm(sub(p[0], p[1])) * norm(sub(p[2], p[3])), b = norm(sub(p[0], p[2])) * norm(sub(p[1], p[3])),
                 c = norm(sub(p[0], p[3])) * norm(sub(p[1], p[2]));
    const double circumradius = std::sqrt(std::max(0.0, (a + b + c) * (a + b - c) * (a - b + c) * (-a + b + c))) / (24 * volume);
    const double ratio = 3 * (3 * volume / area) / circumradius;
    q.min_radius_ratio = std::min(q.min_radius_ratio, ratio);
    ++q.radius_ratio_histogram[std::clamp(static_cast<int>(ratio * 10), 0, 9)];
  }
  if (tets.empty()) q.min_dihedral_deg = 0, q.min_radius_ratio = 0;
  return q;
}

VolumeMesh mesh_mask(const MaskVolume& mask, const MeshingSettings& s) {
  if (!(s.element_size_mm > 0)) throw std::runtime_error("meshing: the element size must be positive");
  VolumeMesh out;
  long voxels = 0;
  for (auto v : mask.data) voxels += v != 0;
  if (voxels == 0) throw std::runtime_error("meshing: the segmentation is empty (no voxel set)");
  const double voxel_mm3 = mask.spacing_mm[0] * mask.spacing_mm[1] * mask.spacing_mm[2];
  out.segmented_volume_m3 = voxels * voxel_mm3 * 1e-9;
  const double estimate = voxels * voxel_mm3 / (std::pow(s.element_size_mm, 3) / (6 * std::sqrt(2.0))) ;
  if (estimate > 2e7)
    throw std::runtime_error("meshing: an element size of " + std::to_string(s.element_size_mm) + " mm would make about " +
                             std::to_string(static_cast<long>(estimate)) + " tetrahedra, more than memory allows (20 million)");

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
  auto smooth = vtkSmartPointer<vtkWindowedSincPolyDataFilter>::New();
  smooth->SetInputConnection(clean->GetOutputPort());
  smooth->SetNumberOfIterations(s.smoothing_iterations);
  smooth->SetPassBand(0.1);
  smooth->BoundarySmoothingOff();
  smooth->FeatureEdgeSmoothingOff();
  smooth->NonManifoldSmoothingOn();
  smooth->NormalizeCoordinatesOn();
  smooth->Update();
  auto mass = vtkSmartPointer<vtkMassProperties>::New();
  mass->SetInputConnection(smooth->GetOutputPort());
  mass->Update();
  const double triangle_area = std::sqrt(3.0) / 4 * s.element_size_mm * s.element_size_mm;
  const double wanted = std::max(200.0, mass->GetSurfaceArea() / triangle_area);
  const double have = smooth->GetOutput()->GetNumberOfPolys();
  vtkSmartPointer<vtkPolyData> surface = smooth->GetOutput();
  if (wanted < have) {
    auto decimate = vtkSmartPointer<vtkQuadricDecimation>::New();
    decimate->SetInputData(surface);
    decimate->SetTargetReduction(1 - wanted / have);
    decimate->VolumePreservationOn();
    decimate->Update();
    surface = decimate->GetOutput();
  }
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
  // decimated triangles are too uneven for good tetrahedra next to them). A surface it cannot
  // parametrise (a shape with handles, like a spine's) is kept as it is.
  std::vector<int> patch_tags{1};
  try {
    add_surface();
    gmsh::model::mesh::classifySurfaces(40 * M_PI / 180, true, true, M_PI);
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
  gmsh::option::setNumber("Mesh.MeshSizeMin", 0.2 * h);
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
  const auto extract = [&] {
    out.nodes_m.clear(), out.tetrahedra.clear(), out.boundary.clear();
    std::vector<std::size_t> all_tags, element_tags, element_nodes;  // Gmsh takes non-empty vectors as preallocated
    std::vector<double> all_coordinates, parametric;
    gmsh::model::mesh::getNodes(all_tags, all_coordinates, parametric, -1, -1, false, false);
    std::map<std::size_t, int> index;
    for (std::size_t i = 0; i < all_tags.size(); ++i) {
      index[all_tags[i]] = static_cast<int>(i);
      out.nodes_m.push_back({all_coordinates[3 * i], all_coordinates[3 * i + 1], all_coordinates[3 * i + 2]});
    }
    gmsh::model::mesh::getElementsByType(4, element_tags, element_nodes, -1);
    if (element_nodes.empty()) throw std::runtime_error("meshing: Gmsh made no tetrahedra");
    for (std::size_t e = 0; e < element_nodes.size(); e += 4) {
      std::array<int, 4> t{index.at(element_nodes[e]), index.at(element_nodes[e + 1]), index.at(element_nodes[e + 2]),
                           index.at(element_nodes[e + 3])};
      if (signed_volume(out.nodes_m, t) < 0) std::swap(t[2], t[3]);
      out.tetrahedra.push_back(t);
    }
    element_tags.clear(), element_nodes.clear();
    gmsh::model::mesh::getElementsByType(2, element_tags, element_nodes, -1);
    for (std::size_t e = 0; e < element_nodes.size(); e += 3)
      out.boundary.push_back({index.at(element_nodes[e]), index.at(element_nodes[e + 1]), index.at(element_nodes[e + 2])});
    out.quality = mesh_quality(out.nodes_m, out.tetrahedra);
  };
  try {
    extract();
    // Slivers left: optimise again, more widely, and move nodes.
    for (int pass = 0; pass < 4 && out.quality.min_dihedral_deg < 10; ++pass) {
      gmsh::option::setNumber("Mesh.OptimizeThreshold", 0.6 + 0.1 * pass);
      gmsh::model::mesh::optimize("", false, 1);
      gmsh::model::mesh::optimize("Relocate3D");
      extract();
    }
  } catch (const std::string& e) {
    throw std::runtime_error("meshing: Gmsh: " + e);
  }
  out.volume_m3 = out.quality.volume_m3;
  report(s, "done", 1.0);
  return out;
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
    for (const auto& t : mesh.tetrahedra) {
      const vtkIdType v[4] = {t[0], t[1], t[2], t[3]};
      grid->InsertNextCell(VTK_TETRA, 4, v);
      boundary->InsertNextValue(-1), material->InsertNextValue(0);
    }
    for (const auto& t : mesh.boundary) {
      const vtkIdType v[3] = {t[0], t[1], t[2]};
      grid->InsertNextCell(VTK_TRIANGLE, 3, v);
      boundary->InsertNextValue(0), material->InsertNextValue(-1);
    }
    grid->GetCellData()->AddArray(boundary);
    grid->GetCellData()->AddArray(material);
    auto names = vtkSmartPointer<vtkStringArray>::New();
    names->SetName("boundary_names");
    names->InsertNextValue("surface");
    grid->GetFieldData()->AddArray(names);
    auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
    writer->SetFileName(name.c_str());
    writer->SetInputData(grid);
    if (!writer->Write()) throw std::runtime_error(name + ": could not be written");
    return;
  }
  if (e != ".msh") throw std::runtime_error(name + ": meshes are written as .msh or .vtu");
  GmshSession session;
  gmsh::model::add("tissue");
  gmsh::model::addDiscreteEntity(2, 1);
  gmsh::model::addDiscreteEntity(3, 1, {1});
  std::vector<std::size_t> tags(mesh.nodes_m.size());
  std::vector<double> xyz;
  for (std::size_t i = 0; i < tags.size(); ++i) {
    tags[i] = i + 1;
    xyz.insert(xyz.end(), mesh.nodes_m[i].begin(), mesh.nodes_m[i].end());
  }
  gmsh::model::mesh::addNodes(3, 1, tags, xyz);
  std::vector<std::size_t> tri, tet;
  for (const auto& t : mesh.boundary) for (int v : t) tri.push_back(std::size_t(v) + 1);
  for (const auto& t : mesh.tetrahedra) for (int v : t) tet.push_back(std::size_t(v) + 1);
  gmsh::model::mesh::addElementsByType(1, 2, {}, tri);
  gmsh::model::mesh::addElementsByType(1, 4, {}, tet);
  gmsh::model::addPhysicalGroup(2, {1}, 1);
  gmsh::model::setPhysicalName(2, 1, "surface");
  gmsh::model::addPhysicalGroup(3, {1}, 2);
  gmsh::model::setPhysicalName(3, 2, "tissue");
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
