#include "meshes/mesh_summary.h"

#include "imaging/vtk_message.h"
#include "meshes/mesh_file_checks.h"

#include <gmsh.h>
#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCellTypes.h>
#include <vtkNew.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <mutex>
#include <stdexcept>

namespace fetouch::meshes {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string gmsh_element_name(int type) {
  switch (type) {
    case 1: case 8: return "line";
    case 2: case 9: return "triangle";
    case 3: case 10: return "quadrilateral";
    case 4: case 11: return "tetrahedron";
    case 5: case 12: return "hexahedron";
    case 6: case 13: return "prism";
    case 7: case 14: return "pyramid";
    case 15: return "point";
    default: return "type " + std::to_string(type);
  }
}

// The Gmsh API is one global model per process; keep concurrent readers out of each other's way.
std::mutex gmsh_mutex;

MeshSummary read_gmsh(const std::string& name) {
  std::lock_guard<std::mutex> lock(gmsh_mutex);
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("General.Verbosity", 0);
  gmsh::logger::start();
  MeshSummary summary;
  try {
    gmsh::open(name);
    std::vector<std::string> log;
    gmsh::logger::get(log);
    for (const auto& line : log)
      if (line.rfind("Error", 0) == 0) throw std::runtime_error(name + ": " + line);
    summary.format = "Gmsh";
    std::vector<std::size_t> node_tags;
    std::vector<double> coords, parametric;
    gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, false, false);
    summary.nodes = static_cast<long>(node_tags.size());
    if (!coords.empty()) {
      summary.min_m = {coords[0], coords[1], coords[2]};
      summary.max_m = summary.min_m;
      for (size_t i = 0; i + 2 < coords.size(); i += 3)
        for (int d = 0; d < 3; ++d) {
          summary.min_m[d] = std::min(summary.min_m[d], coords[i + d]);
          summary.max_m[d] = std::max(summary.max_m[d], coords[i + d]);
        }
    }
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> element_tags, element_nodes;
    gmsh::model::mesh::getElements(types, element_tags, element_nodes, -1, -1);
    for (size_t i = 0; i < types.size(); ++i)
      summary.elements[gmsh_element_name(types[i])] += static_cast<long>(element_tags[i].size());
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups, -1);
    for (const auto& [dim, tag] : groups) {
      PhysicalGroup group{dim, tag, ""};
      gmsh::model::getPhysicalName(dim, tag, group.name);
      summary.physical_groups.push_back(group);
    }
  } catch (const std::runtime_error&) {
    gmsh::finalize();
    throw;
  } catch (...) {
    std::vector<std::string> log;
    gmsh::logger::get(log);
    gmsh::finalize();
    throw std::runtime_error(name + ": Gmsh could not read it" +
                             (log.empty() ? std::string() : " (" + log.back() + ")"));
  }
  gmsh::finalize();
  if (summary.nodes == 0) throw std::runtime_error(name + ": the mesh has no nodes");
  return summary;
}

struct VtkErrors {
  std::string text;
  static void on_error(vtkObject*, unsigned long, void* client, void* data) {
    auto* self = static_cast<VtkErrors*>(client);
    if (data && self->text.empty()) self->text = static_cast<const char*>(data);
  }
};

MeshSummary read_vtu(const std::string& name) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  if (!reader->CanReadFile(name.c_str()))
    throw std::runtime_error(name + ": not a VTK unstructured grid (.vtu) file");
  VtkErrors errors;
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(&VtkErrors::on_error);
  callback->SetClientData(&errors);
  reader->AddObserver(vtkCommand::ErrorEvent, callback);
  reader->SetFileName(name.c_str());
  reader->Update();
  if (!errors.text.empty()) throw std::runtime_error(name + ": " + imaging::vtk_message(errors.text));
  vtkUnstructuredGrid* grid = reader->GetOutput();
  MeshSummary summary;
  summary.format = "VTK unstructured grid";
  summary.nodes = grid->GetNumberOfPoints();
  if (summary.nodes == 0) throw std::runtime_error(name + ": the mesh has no points");
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    switch (grid->GetCellType(c)) {
      case VTK_TETRA: case VTK_QUADRATIC_TETRA: ++summary.elements["tetrahedron"]; break;
      case VTK_HEXAHEDRON: case VTK_QUADRATIC_HEXAHEDRON: ++summary.elements["hexahedron"]; break;
      case VTK_TRIANGLE: case VTK_QUADRATIC_TRIANGLE: ++summary.elements["triangle"]; break;
      case VTK_QUAD: ++summary.elements["quadrilateral"]; break;
      case VTK_WEDGE: ++summary.elements["prism"]; break;
      case VTK_PYRAMID: ++summary.elements["pyramid"]; break;
      default: ++summary.elements[std::string("VTK cell ") +
                                  vtkCellTypes::GetClassNameFromTypeId(grid->GetCellType(c))];
    }
  }
  double bounds[6];
  grid->GetBounds(bounds);
  summary.min_m = {bounds[0], bounds[2], bounds[4]};
  summary.max_m = {bounds[1], bounds[3], bounds[5]};
  return summary;
}

}  // namespace

long MeshSummary::count(const std::string& element_type) const {
  auto it = elements.find(element_type);
  return it == elements.end() ? 0 : it->second;
}

bool MeshSummary::has_group(const std::string& name) const {
  return std::any_of(physical_groups.begin(), physical_groups.end(),
                     [&](const PhysicalGroup& g) { return g.name == name; });
}

MeshSummary read_mesh_summary(const std::filesystem::path& path) {
  const std::string name = path.string();
  if (ends_with(name, ".msh") || ends_with(name, ".vtu")) check_mesh_file(path);
  if (ends_with(name, ".msh")) return read_gmsh(name);
  if (ends_with(name, ".vtu")) return read_vtu(name);
  throw std::runtime_error(name + ": unknown mesh format; expected .msh (Gmsh 4) or .vtu");
}

}  // namespace fetouch::meshes
