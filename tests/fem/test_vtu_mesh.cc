// Meshes from .vtu files (fem/vtu_mesh.h): a block written with VTK's own cell conventions (checked
// by VTK's cell-size filter: every cell's volume positive, the block's volume in total) reads back
// with the same volume, named boundary regions of the right areas and region ids, and solves to the
// same answer as the mesh it was written from. Broken files are refused with the file named.
#include <gtest/gtest.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>
#include <unistd.h>
#include <vtkCellData.h>
#include <vtkCellSizeFilter.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "fem/material.h"
#include "fem/quasi_static_solver.h"
#include "fem/vtu_mesh.h"

namespace fetouch::fem {
namespace {

using dealii::Point;
using dealii::Tensor;

const Point<3> kSize(0.1, 0.08, 0.05);

void block(dealii::Triangulation<3>& tria, bool simplex) {
  if (simplex)
    dealii::GridGenerator::subdivided_hyper_rectangle_with_simplices(tria, {3, 2, 2}, Point<3>(), kSize);
  else
    dealii::GridGenerator::subdivided_hyper_rectangle(tria, {3, 2, 2}, Point<3>(), kSize);
  for (const auto& cell : tria.active_cell_iterators()) {
    cell->set_material_id(cell->center()[0] < 0.05 ? 0 : 3);
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary()) {
        const double z = cell->face(f)->center()[2];
        cell->face(f)->set_boundary_id(std::abs(z) < 1e-12 ? 0 : std::abs(z - kSize[2]) < 1e-12 ? 1 : 2);
      }
  }
}

// The triangulation as a VTK grid in VTK's vertex orders, with every other tetrahedron flipped
// (negative orientation, which the reader must repair), boundary faces as surface cells.
vtkSmartPointer<vtkUnstructuredGrid> to_vtk(const dealii::Triangulation<3>& tria) {
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();  // VTK's default is single precision
  for (const Point<3>& v : tria.get_vertices()) points->InsertNextPoint(v[0], v[1], v[2]);
  grid->SetPoints(points);
  auto material = vtkSmartPointer<vtkIntArray>::New(), boundary = vtkSmartPointer<vtkIntArray>::New();
  material->SetName("material_id");
  boundary->SetName("boundary_id");
  int k = 0;
  for (const auto& cell : tria.active_cell_iterators()) {
    if (cell->reference_cell() == dealii::ReferenceCells::Tetrahedron) {
      vtkIdType v[4] = {cell->vertex_index(0), cell->vertex_index(1), cell->vertex_index(2), cell->vertex_index(3)};
      if (k++ % 2) std::swap(v[2], v[3]);
      grid->InsertNextCell(VTK_TETRA, 4, v);
    } else {
      const int order[8] = {0, 1, 3, 2, 4, 5, 7, 6};
      vtkIdType v[8];
      for (int i = 0; i < 8; ++i) v[i] = cell->vertex_index(order[i]);
      grid->InsertNextCell(VTK_HEXAHEDRON, 8, v);
    }
    material->InsertNextValue(cell->material_id());
    boundary->InsertNextValue(-1);
  }
  for (const auto& cell : tria.active_cell_iterators())
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const auto face = cell->face(f);
      if (face->n_vertices() == 3) {
        vtkIdType v[3] = {face->vertex_index(0), face->vertex_index(1), face->vertex_index(2)};
        grid->InsertNextCell(VTK_TRIANGLE, 3, v);
      } else {
        vtkIdType v[4] = {face->vertex_index(0), face->vertex_index(1), face->vertex_index(3), face->vertex_index(2)};
        grid->InsertNextCell(VTK_QUAD, 4, v);
      }
      material->InsertNextValue(-1);
      boundary->InsertNextValue(face->boundary_id());
    }
  grid->GetCellData()->AddArray(material);
  grid->GetCellData()->AddArray(boundary);
  auto names = vtkSmartPointer<vtkStringArray>::New();
  names->SetName("boundary_names");
  names->InsertNextValue("table");
  names->InsertNextValue("top");
  names->InsertNextValue("sides");
  grid->GetFieldData()->AddArray(names);
  return grid;
}

std::string write(vtkUnstructuredGrid* grid, const std::string& name) {
  const std::string path =
      (std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".vtu")).string();
  auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputData(grid);
  writer->Write();
  return path;
}

double top_sink(const dealii::Triangulation<3>& tria) {
  const NeoHookean material(lame_lambda(5000, 0.45), lame_mu(5000, 0.45));
  const NeoHookean harder(lame_lambda(50000, 0.45), lame_mu(50000, 0.45));
  QuasiStaticSolver solver(tria, material, 1);
  solver.set_region_material(3, harder);
  solver.prescribe_displacement(0, {true, true, true}, Tensor<1, 3>());
  Tensor<1, 3> t;
  t[2] = -200;
  solver.apply_traction(1, t);
  EXPECT_TRUE(solver.solve(NewtonSettings{}).converged);
  return solver.displacement_at(Point<3>(0.03, 0.04, 0.05))[2];
}

TEST(VtuMesh, ReadsWhatVtkWroteWithRegionsAndSolvesTheSame) {
  for (const bool simplex : {true, false}) {
    dealii::Triangulation<3> original;
    block(original, simplex);
    auto grid = to_vtk(original);
    // VTK's own judgement of the cells (the volume cells only: the surface cells come last).
    auto sizes = vtkSmartPointer<vtkCellSizeFilter>::New();
    sizes->SetInputData(grid);
    sizes->Update();
    vtkDataArray* volume = vtkDataSet::SafeDownCast(sizes->GetOutput())->GetCellData()->GetArray("Volume");
    double total = 0;
    for (unsigned int c = 0; c < original.n_active_cells(); ++c) total += std::abs(volume->GetTuple1(c));
    const double box = kSize[0] * kSize[1] * kSize[2];
    EXPECT_NEAR(total, box, 1e-12 * box);
    const std::string path = write(grid, simplex ? "tets" : "hexes");

    dealii::Triangulation<3> read;
    const auto names = read_vtu_mesh(path, read);
    std::filesystem::remove(path);
    EXPECT_EQ(read.n_active_cells(), original.n_active_cells());
    double measure = 0;
    std::map<unsigned int, double> area;
    std::map<unsigned int, int> materials;
    for (const auto& cell : read.active_cell_iterators()) {
      EXPECT_GT(cell->measure(), 0.0);
      measure += cell->measure();
      ++materials[cell->material_id()];
      for (const unsigned int f : cell->face_indices())
        if (cell->face(f)->at_boundary()) area[cell->face(f)->boundary_id()] += cell->face(f)->measure();
    }
    EXPECT_NEAR(measure, box, 1e-12 * box);
    ASSERT_EQ(names.size(), 3u);
    EXPECT_EQ(names.at("table"), 0u);
    EXPECT_EQ(names.at("top"), 1u);
    EXPECT_EQ(names.at("sides"), 2u);
    EXPECT_NEAR(area[0], kSize[0] * kSize[1], 1e-12);
    EXPECT_NEAR(area[1], kSize[0] * kSize[1], 1e-12);
    EXPECT_NEAR(area[2], 2 * (kSize[0] + kSize[1]) * kSize[2], 1e-12);
    EXPECT_EQ(materials.size(), 2u);
    const double a = top_sink(original), b = top_sink(read);
    std::printf("%s: top sinks %.10e m on the original mesh, %.10e m read from .vtu\n", simplex ? "P1" : "Q1", a, b);
    EXPECT_NEAR(a, b, 1e-10 * std::abs(a));
  }
}

TEST(VtuMesh, BrokenFilesAreRefusedByName) {
  dealii::Triangulation<3> tria;
  EXPECT_THROW(read_vtu_mesh("/nonexistent/mesh.vtu", tria), std::runtime_error);
  const std::string junk = (std::filesystem::temp_directory_path() / ("junk_" + std::to_string(::getpid()) + ".vtu")).string();
  std::ofstream(junk) << "<VTKFile type=\"UnstructuredGrid\"><truncated";
  try {
    read_vtu_mesh(junk, tria);
    ADD_FAILURE() << "a truncated file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(junk), std::string::npos) << e.what();
  }
  std::filesystem::remove(junk);
  // Only a surface: no volume cells.
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->InsertNextPoint(0, 0, 0), points->InsertNextPoint(1, 0, 0), points->InsertNextPoint(0, 1, 0);
  grid->SetPoints(points);
  vtkIdType v[3] = {0, 1, 2};
  grid->InsertNextCell(VTK_TRIANGLE, 3, v);
  const std::string surface = write(grid, "surface");
  try {
    read_vtu_mesh(surface, tria);
    ADD_FAILURE() << "a surface was accepted as a volume mesh";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no tetrahedra or hexahedra"), std::string::npos) << e.what();
  }
  std::filesystem::remove(surface);
}

// Files that crashed the reader (issue 17): cells that point outside the point array or have the
// wrong number of points for their type, and other nonsense, each refused naming the file and
// the cell, before any of it is used.
TEST(VtuMesh, CellsThatDoNotFitTheirPointsAreRefused) {
  struct Case {
    const char* name;
    std::vector<vtkIdType> corners;  // of one tetrahedron in a 4-point grid
    double x0;                       // the first point's x
    double material;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"past_the_points", {0, 1, 2, 99}, 0, 0, "refers to point 99, outside 0..3"},
      {"negative", {0, -1, 2, 3}, 0, 0, "refers to point -1"},
      {"three_points", {0, 1, 2}, 0, 0, "has 3 points where its type has 4"},
      {"repeated", {0, 1, 2, 2}, 0, 0, "uses the same point twice"},
      {"not_a_number", {0, 1, 2, 3}, std::nan(""), 0, "point 0 has a coordinate that is not a finite number"},
      {"flat", {0, 1, 2, 3}, 0.5, 0, "flat tetrahedron"},  // its four points in z = 0 (below)
      {"material", {0, 1, 2, 3}, 0, 1e9, "material_id"},
  };
  for (const Case& c : cases) {
    auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    const bool flat = std::string(c.name) == "flat";
    points->InsertNextPoint(c.x0, 0, 0), points->InsertNextPoint(1, 0, 0), points->InsertNextPoint(0, 1, 0);
    points->InsertNextPoint(flat ? 0.5 : 0, flat ? 0.5 : 0, flat ? 0 : 1);  // flat: all four in z = 0
    grid->SetPoints(points);
    grid->InsertNextCell(VTK_TETRA, static_cast<vtkIdType>(c.corners.size()), c.corners.data());
    auto material = vtkSmartPointer<vtkIntArray>::New();
    material->SetName("material_id");
    material->InsertNextValue(static_cast<int>(std::min(c.material, 2e9)));
    grid->GetCellData()->AddArray(material);
    const std::string file = write(grid, c.name);
    dealii::Triangulation<3> tria;
    try {
      read_vtu_mesh(file, tria);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file), std::string::npos) << c.name << ": " << what;
      EXPECT_NE(what.find(c.expected), std::string::npos) << c.name << ": " << what;
    }
    std::filesystem::remove(file);
  }
}

}  // namespace
}  // namespace fetouch::fem
