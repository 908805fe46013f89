#include "app/trainer/tissue_view.h"

#include <vtkActor.h>
#include <vtkArrowSource.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkFloatArray.h>
#include <vtkLookupTable.h>
#include <vtkMatrix4x4.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSphereSource.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace fetouch::app::trainer {

namespace {

vtkSmartPointer<vtkActor> sphere_actor(double radius, double r, double g, double b) {
  auto source = vtkSmartPointer<vtkSphereSource>::New();
  source->SetRadius(radius);
  source->SetThetaResolution(20), source->SetPhiResolution(14);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputConnection(source->GetOutputPort());
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(r, g, b);
  return actor;
}

vtkSmartPointer<vtkPolyData> triangles(vtkPoints* points, const std::vector<std::array<unsigned int, 3>>& list) {
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& t : list) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    cells->InsertNextCell(3, ids);
  }
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  data->SetPolys(cells);
  return data;
}

}  // namespace

TissueView::TissueView(vtkRenderer* renderer, const MeshView& mesh, const std::vector<double>& probe_radii_m)
    : renderer_(renderer), mesh_(mesh) {
  points_ = vtkSmartPointer<vtkPoints>::New();
  points_->SetDataTypeToDouble();
  points_->SetNumberOfPoints(static_cast<vtkIdType>(mesh.points.size()));
  for (std::size_t i = 0; i < mesh.points.size(); ++i) points_->SetPoint(static_cast<vtkIdType>(i), mesh.points[i].data());
  // Interfaces: faces of two tetrahedra of different regions.
  std::map<std::array<unsigned int, 3>, std::pair<std::size_t, int>> faces;  // sorted face -> first holder, count
  std::vector<std::array<unsigned int, 3>> inner;
  std::vector<unsigned int> inner_cell;
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (const auto& f : kFace) {
      std::array<unsigned int, 3> key = {mesh.tetrahedra[t][f[0]], mesh.tetrahedra[t][f[1]], mesh.tetrahedra[t][f[2]]};
      std::sort(key.begin(), key.end());
      auto [at, fresh] = faces.emplace(key, std::make_pair(t, 1));
      if (fresh) continue;
      if (mesh.material[at->second.first] != mesh.material[t]) {
        inner.push_back(key);
        inner_cell.push_back(mesh.tetrahedron_cell[t]);
      }
    }
  interfaces_ = inner.size();
  triangle_cell_ = mesh.boundary_triangle_cell;
  triangle_cell_.insert(triangle_cell_.end(), inner_cell.begin(), inner_cell.end());

  magnitude_ = vtkSmartPointer<vtkFloatArray>::New();
  magnitude_->SetName("displacement_mm");
  magnitude_->SetNumberOfTuples(static_cast<vtkIdType>(mesh.points.size()));
  magnitude_->Fill(0);
  lookup_ = vtkSmartPointer<vtkLookupTable>::New();
  lookup_->SetHueRange(0.667, 0.0);  // blue (rest) to red
  lookup_->Build();

  surface_ = triangles(points_, mesh.boundary_triangles);
  surface_->GetPointData()->SetScalars(magnitude_);
  stress_ = vtkSmartPointer<vtkFloatArray>::New();
  stress_->SetName("von_mises_kpa");
  stress_->SetNumberOfTuples(static_cast<vtkIdType>(mesh.boundary_triangles.size()));
  stress_->Fill(0);
  surface_->GetCellData()->SetScalars(stress_);
  surface_mapper_ = vtkSmartPointer<vtkPolyDataMapper>::New();
  surface_mapper_->SetInputData(surface_);
  surface_mapper_->SetLookupTable(lookup_);
  surface_mapper_->SetScalarModeToUsePointData();
  surface_actor_ = vtkSmartPointer<vtkActor>::New();
  surface_actor_->SetMapper(surface_mapper_);
  surface_actor_->GetProperty()->BackfaceCullingOff();
  renderer_->AddActor(surface_actor_);
  if (interfaces_ > 0) {
    surface_actor_->GetProperty()->SetOpacity(0.3);  // the wall, see-through: the inner structures show
    inner_ = triangles(points_, inner);
    inner_->GetPointData()->SetScalars(magnitude_);
    auto inner_stress = vtkSmartPointer<vtkFloatArray>::New();
    inner_stress->SetNumberOfTuples(static_cast<vtkIdType>(inner.size()));
    inner_stress->Fill(0);
    inner_->GetCellData()->SetScalars(inner_stress);
    inner_mapper_ = vtkSmartPointer<vtkPolyDataMapper>::New();
    inner_mapper_->SetInputData(inner_);
    inner_mapper_->SetLookupTable(lookup_);
    inner_mapper_->SetScalarModeToUsePointData();
    inner_actor_ = vtkSmartPointer<vtkActor>::New();
    inner_actor_->SetMapper(inner_mapper_);
    renderer_->AddActor(inner_actor_);
  }
  bar_ = vtkSmartPointer<vtkScalarBarActor>::New();
  bar_->SetLookupTable(lookup_);
  bar_->SetTitle("|u| (mm)");
  bar_->SetNumberOfLabels(4);
  bar_->SetWidth(0.08), bar_->SetHeight(0.45);
  bar_->GetTitleTextProperty()->SetFontSize(12);
  renderer_->AddActor2D(bar_);

  for (double radius : probe_radii_m) {
    ProbeActors a;
    a.tool = sphere_actor(radius, 0.2, 0.8, 0.3);
    a.proxy = sphere_actor(0.35 * radius, 1.0, 0.9, 0.1);
    auto arrow = vtkSmartPointer<vtkArrowSource>::New();
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(arrow->GetOutputPort());
    a.arrow = vtkSmartPointer<vtkActor>::New();
    a.arrow->SetMapper(mapper);
    a.arrow->GetProperty()->SetColor(1.0, 0.3, 0.1);
    a.arrow->VisibilityOff();
    for (auto* actor : {a.tool.Get(), a.proxy.Get(), a.arrow.Get()}) renderer_->AddActor(actor);
    probes_.push_back(a);
  }
  cursor_ = sphere_actor(probe_radii_m.empty() ? 0.004 : 0.6 * probe_radii_m.front(), 0.9, 0.9, 0.9);
  cursor_->GetProperty()->SetRepresentationToWireframe();
  cursor_->VisibilityOff();
  renderer_->AddActor(cursor_);
  renderer_->SetBackground(0.12, 0.13, 0.16);
}

TissueView::~TissueView() = default;

void TissueView::update_tissue(const TissueSnapshot& s, ColourField field) {
  const std::size_t n = mesh_.points.size();
  const bool moved = s.displacement.size() == 3 * n;
  float largest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double p[3] = {mesh_.points[i][0], mesh_.points[i][1], mesh_.points[i][2]};
    float magnitude = 0;
    if (moved) {
      const float* u = &s.displacement[3 * i];
      for (int c = 0; c < 3; ++c) p[c] += u[c];
      magnitude = 1e3f * std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    }
    points_->SetPoint(static_cast<vtkIdType>(i), p);
    magnitude_->SetValue(static_cast<vtkIdType>(i), magnitude);
    largest = std::max(largest, magnitude);
  }
  points_->Modified();
  magnitude_->Modified();
  const bool stress = field == ColourField::von_mises && s.von_mises.size() == mesh_.cells;
  if (stress) {
    float top = 0;
    const std::size_t outer = mesh_.boundary_triangles.size();
    auto* inner = inner_ ? vtkFloatArray::SafeDownCast(inner_->GetCellData()->GetScalars()) : nullptr;
    for (std::size_t t = 0; t < triangle_cell_.size(); ++t) {
      const float kpa = 1e-3f * static_cast<float>(s.von_mises[triangle_cell_[t]]);
      top = std::max(top, kpa);
      if (t < outer)
        stress_->SetValue(static_cast<vtkIdType>(t), kpa);
      else if (inner)
        inner->SetValue(static_cast<vtkIdType>(t - outer), kpa);
    }
    stress_->Modified();
    if (inner) inner->Modified();
    largest = top;
  }
  const bool cells = stress;
  for (auto* mapper : {surface_mapper_.Get(), inner_mapper_.Get()}) {
    if (!mapper) continue;
    if (cells)
      mapper->SetScalarModeToUseCellData();
    else
      mapper->SetScalarModeToUsePointData();
    // A range that never collapses: at rest the colours stay blue.
    mapper->SetScalarRange(0, std::max(largest, cells ? 0.1f : 0.5f));
  }
  bar_->SetTitle(cells ? "von Mises (kPa)" : "|u| (mm)");
  surface_->Modified();
  if (inner_) inner_->Modified();
}

void TissueView::update_probes(const std::array<SessionMonitor::ProbeTick, SessionMonitor::kMaxDevices>& probes, int count) {
  for (int p = 0; p < count && p < static_cast<int>(probes_.size()); ++p) {
    const auto& t = probes[p];
    probes_[p].tool->SetPosition(t.position.x(), t.position.y(), t.position.z());
    probes_[p].proxy->SetPosition(t.proxy.x(), t.proxy.y(), t.proxy.z());
    probes_[p].proxy->SetVisibility(t.in_contact);
    const double force = t.force.norm();
    if (force < 1e-3) {
      probes_[p].arrow->VisibilityOff();
      continue;
    }
    // The arrow from the proxy along the force, 2 cm per newton (at least 5 mm).
    const Eigen::Vector3d x = t.force / force;
    Eigen::Vector3d y = x.cross(Eigen::Vector3d::UnitZ());
    if (y.norm() < 1e-3) y = x.cross(Eigen::Vector3d::UnitY());
    y.normalize();
    const Eigen::Vector3d z = x.cross(y);
    const double length = std::max(0.005, 0.02 * force);
    auto m = vtkSmartPointer<vtkMatrix4x4>::New();
    for (int r = 0; r < 3; ++r) {
      m->SetElement(r, 0, x[r] * length), m->SetElement(r, 1, y[r] * length), m->SetElement(r, 2, z[r] * length);
      m->SetElement(r, 3, t.proxy[r]);
    }
    probes_[p].arrow->SetUserMatrix(m);
    probes_[p].arrow->VisibilityOn();
  }
}

void TissueView::show_cursor(bool on, const Eigen::Vector3d& at) {
  cursor_->SetVisibility(on);
  if (on) cursor_->SetPosition(at.x(), at.y(), at.z());
}

void TissueView::reset_camera() {
  renderer_->ResetCamera(surface_->GetBounds());
  renderer_->GetActiveCamera()->Zoom(1.1);
}

}  // namespace fetouch::app::trainer
