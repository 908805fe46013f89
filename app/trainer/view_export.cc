#include "app/trainer/view_export.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkFieldData.h>
#include <vtkPoints.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <map>
#include <sstream>
#include <stdexcept>

namespace fetouch::app::trainer {

void write_tissue_vtu(const MeshView& mesh, const std::vector<float>& displacement, const std::filesystem::path& file) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (const auto& p : mesh.points) points->InsertNextPoint(p.data());
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  vtkNew<vtkIntArray> material;
  material->SetName("material_id");
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const vtkIdType ids[4] = {mesh.tetrahedra[t][0], mesh.tetrahedra[t][1], mesh.tetrahedra[t][2], mesh.tetrahedra[t][3]};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
    material->InsertNextValue(t < mesh.material.size() ? static_cast<int>(mesh.material[t]) : 0);
  }
  grid->GetCellData()->AddArray(material);
  vtkNew<vtkDoubleArray> u;
  u->SetName("displacement");
  u->SetNumberOfComponents(3);
  u->SetNumberOfTuples(static_cast<vtkIdType>(mesh.points.size()));
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
    for (int c = 0; c < 3; ++c) u->SetComponent(vtkIdType(i), c, 3 * i + 2 < displacement.size() ? displacement[3 * i + c] : 0.0);
  grid->GetPointData()->AddArray(u);
  grid->GetPointData()->SetActiveVectors("displacement");
  vtkNew<vtkStringArray> names;
  names->SetName("region_names");
  for (const auto& [id, name] : mesh.region_name) names->InsertNextValue(std::to_string(id) + " " + name);
  grid->GetFieldData()->AddArray(names);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputData(grid);
  if (writer->Write() != 1) throw std::runtime_error("cannot write " + file.string());
}

MeshView read_tissue_vtu(const std::filesystem::path& file) {
  const std::string name = file.string();
  if (!std::filesystem::is_regular_file(file)) throw std::runtime_error(name + ": no such file");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(name.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !grid || grid->GetNumberOfPoints() == 0)
    throw std::runtime_error(name + ": not a VTK unstructured grid with points (is it a mesh the trainer wrote?)");
  MeshView mesh;
  mesh.points.resize(static_cast<std::size_t>(grid->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) grid->GetPoint(i, mesh.points[static_cast<std::size_t>(i)].data());
  vtkDataArray* material = grid->GetCellData()->GetArray("material_id");
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA) continue;
    vtkIdType count = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(c, count, ids);
    std::array<unsigned int, 4> t{};
    for (int k = 0; k < 4; ++k) {
      if (count != 4 || ids[k] < 0 || ids[k] >= grid->GetNumberOfPoints())
        throw std::runtime_error(name + ": cell " + std::to_string(c) + " refers to point " + std::to_string(count == 4 ? ids[k] : -1) +
                                 ", of " + std::to_string(grid->GetNumberOfPoints()));
      t[k] = static_cast<unsigned int>(ids[k]);
    }
    mesh.tetrahedron_cell.push_back(static_cast<unsigned int>(mesh.tetrahedra.size()));
    mesh.tetrahedra.push_back(t);
    mesh.material.push_back(material ? static_cast<unsigned int>(material->GetTuple1(c)) : 0u);
  }
  if (mesh.tetrahedra.empty()) throw std::runtime_error(name + ": has no tetrahedra");
  mesh.cells = static_cast<unsigned int>(mesh.tetrahedra.size());
  if (auto* names = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("region_names")))
    for (vtkIdType i = 0; i < names->GetNumberOfValues(); ++i) {
      std::istringstream line(names->GetValue(i));
      unsigned int id = 0;
      std::string region;
      if (line >> id && std::getline(line >> std::ws, region)) mesh.region_name[id] = region;
    }
  // The outer surface: the faces no second tetrahedron shares.
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  std::map<std::array<unsigned int, 3>, std::pair<int, std::size_t>> faces;  // sorted face -> (holders, the first)
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (const auto& f : kFace) {
      std::array<unsigned int, 3> key = {mesh.tetrahedra[t][f[0]], mesh.tetrahedra[t][f[1]], mesh.tetrahedra[t][f[2]]};
      std::sort(key.begin(), key.end());
      auto& holder = faces.try_emplace(key, 0, t).first->second;
      ++holder.first;
    }
  for (const auto& [key, holder] : faces)
    if (holder.first == 1) mesh.boundary_triangles.push_back(key), mesh.boundary_triangle_cell.push_back(static_cast<unsigned int>(holder.second));
  return mesh;
}

void write_grey_png(const std::vector<std::uint8_t>& image, int columns, int rows, const std::filesystem::path& file) {
  vtkNew<vtkImageData> picture;
  picture->SetDimensions(columns, rows, 1);
  vtkNew<vtkUnsignedCharArray> grey;
  grey->SetNumberOfTuples(vtkIdType(columns) * rows);
  for (int j = 0; j < rows; ++j)  // VTK's rows go up
    for (int i = 0; i < columns; ++i)
      grey->SetValue(vtkIdType(rows - 1 - j) * columns + i, image[std::size_t(j) * columns + i]);
  picture->GetPointData()->SetScalars(grey);
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputData(picture);
  writer->Write();
  if (writer->GetErrorCode() != 0 || !std::filesystem::exists(file)) throw std::runtime_error("cannot write " + file.string());
}

}  // namespace fetouch::app::trainer
