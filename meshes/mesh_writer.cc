// A volume mesh written as Gmsh .msh 4.1 or VTK .vtu (meshes/volume_mesher.h's write_volume_mesh).
#include "meshes/gmsh_session.h"
#include "meshes/volume_mesher.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <map>
#include <stdexcept>

namespace fetouch::meshes {

namespace {

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

}  // namespace

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
    for (const auto& [group, faces] : interface_groups(mesh)) names->InsertNextValue(group);
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
    // LZ4 rather than zlib: a head at 2 mm (4 million elements) is written in a third of the time.
    writer->SetCompressorTypeToLZ4();
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
