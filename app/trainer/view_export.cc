#include "app/trainer/view_export.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

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
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputData(grid);
  if (writer->Write() != 1) throw std::runtime_error("cannot write " + file.string());
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
