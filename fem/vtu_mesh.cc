#include "fem/vtu_mesh.h"

#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/tria_description.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

namespace fetouch::fem {

using dealii::Point;

namespace {

// Corners of the cell types read here; 0 for any other type.
int corners_of(int type) {
  switch (type) {
    case VTK_TETRA: return 4;
    case VTK_HEXAHEDRON: return 8;
    case VTK_TRIANGLE: return 3;
    case VTK_QUAD: return 4;
    default: return 0;
  }
}

double signed_volume(const std::vector<Point<3>>& v, const std::vector<unsigned int>& c) {
  return ((v[c[1]] - v[c[0]]) * dealii::cross_product_3d(v[c[2]] - v[c[0]], v[c[3]] - v[c[0]])) / 6;
}

// Surface cells on faces inside the volume (a mesher's interfaces between regions, named surface
// groups) bound nothing: deal.II holds boundary ids on boundary faces only, so they are left out,
// and so are ids that only they had.
void drop_inner_faces(const std::vector<dealii::CellData<3>>& cells, dealii::SubCellData& faces,
                      std::set<unsigned int>& boundary_ids) {
  static const std::vector<std::vector<int>> tet_faces{{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  static const std::vector<std::vector<int>> hex_faces{{0, 2, 4, 6}, {1, 3, 5, 7}, {0, 1, 4, 5},
                                                       {2, 3, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}};
  std::map<std::vector<unsigned int>, int> held;
  for (const auto& cell : cells)
    for (const auto& local : cell.vertices.size() == 4 ? tet_faces : hex_faces) {
      std::vector<unsigned int> face;
      for (const int k : local) face.push_back(cell.vertices[std::size_t(k)]);
      std::sort(face.begin(), face.end());
      ++held[face];
    }
  const auto inner = [&](const dealii::CellData<2>& face) {
    std::vector<unsigned int> key = face.vertices;
    std::sort(key.begin(), key.end());
    const auto it = held.find(key);
    return it != held.end() && it->second > 1;
  };
  auto& quads = faces.boundary_quads;
  quads.erase(std::remove_if(quads.begin(), quads.end(), inner), quads.end());
  boundary_ids.clear();
  for (const auto& face : quads) boundary_ids.insert(face.boundary_id);
}

// The cells in the order of a Morton (Z-order) curve through their centroids, 21 bits an axis.
// deal.II keeps the order it is given, numbers the dofs as it meets them cell by cell, and the
// assembly runs in that order: mesh generators leave cells scattered, so that each cell wrote its
// tangent's 144 entries (P1) into rows far apart. Along the curve, neighbouring cells write
// neighbouring rows (the anatomy at 3.6 mm: the tangent's assembly 60-74 -> 42-46 ms).
void order_along_curve(const std::vector<dealii::Point<3>>& vertices, std::vector<dealii::CellData<3>>& cells) {
  dealii::Point<3> low = vertices.empty() ? dealii::Point<3>() : vertices[0], high = low;
  for (const auto& v : vertices)
    for (int d = 0; d < 3; ++d) low[d] = std::min(low[d], v[d]), high[d] = std::max(high[d], v[d]);
  std::vector<std::pair<std::uint64_t, std::size_t>> key(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) {
    dealii::Point<3> centre;
    for (const unsigned int v : cells[k].vertices)
      centre += vertices[v] / static_cast<double>(cells[k].vertices.size());
    std::uint64_t place[3], morton = 0;
    for (int d = 0; d < 3; ++d) {
      const double t = high[d] > low[d] ? (centre[d] - low[d]) / (high[d] - low[d]) : 0.0;
      place[d] = std::min<std::uint64_t>(static_cast<std::uint64_t>(std::clamp(t, 0.0, 1.0) * 2097152.0), 2097151);
    }
    for (int bit = 20; bit >= 0; --bit)
      for (int d = 0; d < 3; ++d) morton = (morton << 1) | ((place[d] >> bit) & 1u);
    key[k] = {morton, k};
  }
  std::sort(key.begin(), key.end());
  std::vector<dealii::CellData<3>> sorted;
  sorted.reserve(cells.size());
  for (const auto& [morton, k] : key) sorted.push_back(std::move(cells[k]));
  cells = std::move(sorted);
}

}  // namespace

std::map<std::string, unsigned int> read_vtu_mesh(const std::string& path, dealii::Triangulation<3>& tria,
                                                  std::map<unsigned int, std::string>* region_names) {
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(path + ": no such file");
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName(path.c_str());
  // VTK's own parser messages would go to the terminal; the errors below say what is wrong.
  const int warnings = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  const bool readable = reader->CanReadFile(path.c_str()) != 0;
  if (readable) reader->Update();
  vtkObject::SetGlobalWarningDisplay(warnings);
  if (!readable) throw std::runtime_error(path + ": not a VTK XML unstructured grid");
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (!grid || grid->GetNumberOfPoints() == 0)
    throw std::runtime_error(path + ": the grid has no points (a truncated or empty file?)");

  std::vector<Point<3>> vertices(grid->GetNumberOfPoints());
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) {
    double x[3];
    grid->GetPoint(i, x);
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
      throw std::runtime_error(path + ": point " + std::to_string(i) + " has a coordinate that is not a finite number");
    vertices[i] = Point<3>(x[0], x[1], x[2]);
  }
  vtkDataArray* material = grid->GetCellData()->GetArray("material_id");
  vtkDataArray* boundary = grid->GetCellData()->GetArray("boundary_id");
  for (vtkDataArray* array : {material, boundary})
    if (array && (array->GetNumberOfComponents() != 1 || array->GetNumberOfTuples() != grid->GetNumberOfCells()))
      throw std::runtime_error(path + ": cell array " + array->GetName() + " has " +
                               std::to_string(array->GetNumberOfTuples()) + " values of " +
                               std::to_string(array->GetNumberOfComponents()) + " components; expected one value per cell (" +
                               std::to_string(grid->GetNumberOfCells()) + ")");

  std::vector<dealii::CellData<3>> cells;
  dealii::SubCellData faces;
  std::set<unsigned int> boundary_ids;
  int volume_type = -1;
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    const int type = grid->GetCellType(c);
    const int corners = corners_of(type);
    if (corners == 0) continue;  // lines, vertices, ...: no part of a volume mesh
    grid->GetCellPoints(c, ids);
    // A file from elsewhere: the cell's point count and every index checked before any is used.
    const std::string cell_name = "cell " + std::to_string(c) + " (VTK type " + std::to_string(type) + ")";
    if (ids->GetNumberOfIds() != corners)
      throw std::runtime_error(path + ": " + cell_name + " has " + std::to_string(ids->GetNumberOfIds()) +
                               " points where its type has " + std::to_string(corners));
    std::vector<unsigned int> v(corners);
    for (int k = 0; k < corners; ++k) {
      const vtkIdType id = ids->GetId(k);
      if (id < 0 || id >= grid->GetNumberOfPoints())
        throw std::runtime_error(path + ": " + cell_name + " refers to point " + std::to_string(id) + ", outside 0.." +
                                 std::to_string(grid->GetNumberOfPoints() - 1));
      v[k] = static_cast<unsigned int>(id);
    }
    if (std::set<unsigned int>(v.begin(), v.end()).size() != v.size())
      throw std::runtime_error(path + ": " + cell_name + " uses the same point twice (a degenerate cell)");
    if (type == VTK_TETRA || type == VTK_HEXAHEDRON) {
      if (volume_type >= 0 && volume_type != type)
        throw std::runtime_error(path + ": mixed tetrahedra and hexahedra are not supported (cell " + std::to_string(c) + ")");
      volume_type = type;
      dealii::CellData<3> cell(type == VTK_TETRA ? 4 : 8);
      if (type == VTK_TETRA) {
        const double volume = signed_volume(vertices, v);
        if (!(std::abs(volume) > 0))
          throw std::runtime_error(path + ": " + cell_name + " is a flat tetrahedron (zero volume)");
        if (volume < 0) std::swap(v[2], v[3]);
        cell.vertices = v;
      } else {  // VTK 0 1 2 3 go around the bottom; deal.II numbers lexicographically
        cell.vertices = {v[0], v[1], v[3], v[2], v[4], v[5], v[7], v[6]};
      }
      const double id = material ? material->GetTuple1(c) : 0;
      if (!(id >= 0 && id <= 255) || id != std::floor(id))
        throw std::runtime_error(path + ": material_id " + std::to_string(id) + " of " + cell_name +
                                 " is not a whole number in 0..255");
      cell.material_id = static_cast<dealii::types::material_id>(id);
      cells.push_back(cell);
    } else if (type == VTK_TRIANGLE || type == VTK_QUAD) {
      if (!boundary) continue;  // untagged surface cells carry no region
      const double id = boundary->GetTuple1(c);
      if (!(id >= 0 && id <= 255) || id != std::floor(id))
        throw std::runtime_error(path + ": boundary_id " + std::to_string(id) + " of " + cell_name +
                                 " is not a whole number in 0..255");
      dealii::CellData<2> face(type == VTK_TRIANGLE ? 3 : 4);
      face.vertices = type == VTK_TRIANGLE ? v : std::vector<unsigned int>{v[0], v[1], v[3], v[2]};
      face.boundary_id = static_cast<dealii::types::boundary_id>(id);
      boundary_ids.insert(static_cast<unsigned int>(id));
      faces.boundary_quads.push_back(face);
    }
  }
  if (cells.empty()) throw std::runtime_error(path + ": no tetrahedra or hexahedra in the grid");
  order_along_curve(vertices, cells);
  drop_inner_faces(cells, faces, boundary_ids);
  tria.clear();
  try {
    dealii::GridTools::delete_unused_vertices(vertices, cells, faces);
    if (volume_type == VTK_HEXAHEDRON) dealii::GridTools::consistently_order_cells(cells);
    tria.create_triangulation(vertices, cells, faces);
  } catch (const std::exception&) {
    throw std::runtime_error(path + ": deal.II could not build the mesh (a boundary cell that is not a face of a volume "
                                    "cell, or cells that do not fit together)");
  }

  std::map<std::string, unsigned int> names;
  auto* labels = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("boundary_names"));
  for (const unsigned int id : boundary_ids) {
    std::string name = "boundary_" + std::to_string(id);
    if (labels && static_cast<vtkIdType>(id) < labels->GetNumberOfValues() && !labels->GetValue(id).empty())
      name = labels->GetValue(id);
    names[name] = id;
  }
  if (region_names)
    if (auto* regions = vtkStringArray::SafeDownCast(grid->GetFieldData()->GetAbstractArray("region_names")))
      for (vtkIdType id = 0; id < regions->GetNumberOfValues(); ++id)
        if (!regions->GetValue(id).empty()) (*region_names)[static_cast<unsigned int>(id)] = regions->GetValue(id);
  return names;
}

}  // namespace fetouch::fem
