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
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSphereSource.h>
#include <vtkTextProperty.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "meshes/tet_geometry.h"

namespace fetouch::app::trainer {

namespace {

constexpr std::array<double, 3> kSkin{0.93, 0.76, 0.68};  // the wall, when regions are coloured

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

// Point normals for shading that reads as a smooth surface (Gouraud), split where neighbouring
// triangles fold by more than 60 degrees (a junction of three surfaces stays a crease).
vtkSmartPointer<vtkPolyDataNormals> smooth_normals(vtkPolyData* data) {
  auto normals = vtkSmartPointer<vtkPolyDataNormals>::New();
  normals->SetInputData(data);
  normals->SetFeatureAngle(60);
  normals->SplittingOn();
  normals->ConsistencyOff();  // the triangles are oriented out of their region already
  normals->AutoOrientNormalsOff();
  normals->ComputePointNormalsOn();
  normals->ComputeCellNormalsOff();
  return normals;
}

double tet_volume(const MeshView& mesh, const std::array<unsigned int, 4>& t) {
  return meshes::tet_signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
}

// The face (sorted or not) ordered so that its normal (b - a) x (c - a) points away from `apex`.
std::array<unsigned int, 3> facing_away(const MeshView& mesh, std::array<unsigned int, 3> f, unsigned int apex) {
  if (tet_volume(mesh, {f[0], f[1], f[2], apex}) > 0) std::swap(f[1], f[2]);
  return f;
}

}  // namespace

TissueView::TissueView(vtkRenderer* renderer, const MeshView& mesh, const std::vector<double>& probe_radii_m,
                       std::vector<LabelSurface> smooth)
    : renderer_(renderer), mesh_(mesh) {
  points_ = vtkSmartPointer<vtkPoints>::New();
  points_->SetDataTypeToDouble();
  points_->SetNumberOfPoints(static_cast<vtkIdType>(mesh.points.size()));
  for (std::size_t i = 0; i < mesh.points.size(); ++i) points_->SetPoint(static_cast<vtkIdType>(i), mesh.points[i].data());
  // Interfaces: faces of two tetrahedra of different regions. Each is drawn once, by the smaller of
  // its two regions (the one inside: the fetus in the fluid, the fluid's wall side by the wall), and
  // oriented out of it; a region hidden shows what it covered.
  std::map<unsigned int, double> region_volume;
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) region_volume[mesh.material[t]] += std::abs(tet_volume(mesh, mesh.tetrahedra[t]));
  const auto owns = [&](unsigned int m, unsigned int other) {
    return region_volume[m] < region_volume[other] || (region_volume[m] == region_volume[other] && m > other);
  };
  std::map<std::array<unsigned int, 3>, std::size_t> first_holder;  // sorted face -> tetrahedron
  std::map<unsigned int, std::size_t> layer_of;                     // material -> layer
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  const auto apex_of = [&](std::size_t t, const std::array<unsigned int, 3>& key) {
    for (unsigned int v : mesh.tetrahedra[t])
      if (v != key[0] && v != key[1] && v != key[2]) return v;
    return mesh.tetrahedra[t][0];
  };
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (const auto& f : kFace) {
      std::array<unsigned int, 3> key = {mesh.tetrahedra[t][f[0]], mesh.tetrahedra[t][f[1]], mesh.tetrahedra[t][f[2]]};
      std::sort(key.begin(), key.end());
      auto [at, fresh] = first_holder.emplace(key, t);
      if (fresh) continue;
      const std::size_t other = at->second;
      if (!smooth.empty() || mesh.material[other] == mesh.material[t]) continue;  // smooth surfaces draw instead
      const std::size_t owner = owns(mesh.material[t], mesh.material[other]) ? t : other;
      const std::size_t across = owner == t ? other : t;
      const unsigned int m = mesh.material[owner];
      auto [slot, added] = layer_of.emplace(m, layers_.size());
      if (added) {
        RegionLayer layer;
        layer.material = m;
        const auto named = mesh.region_name.find(m);
        layer.name = named != mesh.region_name.end() ? named->second : "region " + std::to_string(m);
        layers_.push_back(std::move(layer));
      }
      RegionLayer& layer = layers_[slot->second];
      layer.triangles.push_back(facing_away(mesh, key, apex_of(owner, key)));
      layer.across.push_back(mesh.material[across]);
      layer.cells.push_back(mesh.tetrahedron_cell[owner]);
      ++interfaces_;
    }
  if (!smooth.empty()) {
    // Smooth surfaces instead of the element faces: the same regions draw, each what it shares with
    // a larger one; a triangle's stress is that of the element holding its first corner.
    embedded_ = true;
    for (LabelSurface& surface : smooth) {
      RegionLayer layer;
      layer.material = surface.material;
      const auto named = mesh.region_name.find(surface.material);
      layer.name = named != mesh.region_name.end() ? named->second : "region " + std::to_string(surface.material);
      layer.triangles = surface.triangles;
      layer.across = surface.across;
      for (const auto& t : surface.triangles) layer.cells.push_back(mesh.tetrahedron_cell[surface.tetrahedron[t[0]]]);
      interfaces_ += surface.triangles.size();
      layer.embedded = std::move(surface);
      layers_.push_back(std::move(layer));
    }
  }
  std::sort(layers_.begin(), layers_.end(), [](const RegionLayer& x, const RegionLayer& y) { return x.material < y.material; });
  // The outer surface, oriented outwards (the element under each triangle found by its face).
  std::vector<std::array<unsigned int, 3>> outer = mesh.boundary_triangles;
  std::set<unsigned int> outside;  // the regions on the outer surface (the wall)
  for (auto& f : outer) {
    std::array<unsigned int, 3> key = f;
    std::sort(key.begin(), key.end());
    const auto holder = first_holder.find(key);
    if (holder == first_holder.end()) continue;
    f = facing_away(mesh, f, apex_of(holder->second, key));
    outside.insert(mesh.material[holder->second]);
  }

  magnitude_ = vtkSmartPointer<vtkFloatArray>::New();
  magnitude_->SetName("displacement_mm");
  magnitude_->SetNumberOfTuples(static_cast<vtkIdType>(mesh.points.size()));
  magnitude_->Fill(0);
  lookup_ = vtkSmartPointer<vtkLookupTable>::New();
  lookup_->SetHueRange(0.667, 0.0);  // blue (rest) to red
  lookup_->Build();

  surface_ = triangles(points_, outer);
  surface_->GetPointData()->SetScalars(magnitude_);
  stress_ = vtkSmartPointer<vtkFloatArray>::New();
  stress_->SetName("von_mises_kpa");
  stress_->SetNumberOfTuples(static_cast<vtkIdType>(mesh.boundary_triangles.size()));
  stress_->Fill(0);
  surface_->GetCellData()->SetScalars(stress_);
  surface_normals_ = smooth_normals(surface_);
  surface_mapper_ = vtkSmartPointer<vtkPolyDataMapper>::New();
  surface_mapper_->SetInputConnection(surface_normals_->GetOutputPort());
  surface_mapper_->SetLookupTable(lookup_);
  surface_mapper_->SetScalarModeToUsePointData();
  surface_actor_ = vtkSmartPointer<vtkActor>::New();
  surface_actor_->SetMapper(surface_mapper_);
  surface_actor_->GetProperty()->BackfaceCullingOff();
  renderer_->AddActor(surface_actor_);
  // The wall, see-through: the inner structures show. Its see-through sides are drawn facing the
  // eye only (the near skin, and the far side of the cavity), not also their backs: two see-through
  // layers over the fetus instead of four, which reads it more clearly, and a quarter of a software
  // renderer's frame (Xvfb: 48 -> 37 ms a render, docs/trainer.md).
  const auto see_through = [](vtkActor* actor) {
    actor->GetProperty()->SetOpacity(0.3);
    actor->GetProperty()->BackfaceCullingOn();
  };
  if (interfaces_ > 0) see_through(surface_actor_);
  for (RegionLayer& layer : layers_) {
    if (layer.embedded.points.empty()) {
      layer.data = triangles(points_, layer.triangles);
      layer.data->GetPointData()->SetScalars(magnitude_);
    } else {
      layer.points = vtkSmartPointer<vtkPoints>::New();
      layer.points->SetDataTypeToDouble();
      layer.points->SetNumberOfPoints(static_cast<vtkIdType>(layer.embedded.points.size()));
      for (std::size_t i = 0; i < layer.embedded.points.size(); ++i)
        layer.points->SetPoint(static_cast<vtkIdType>(i), layer.embedded.points[i].data());
      layer.magnitude = vtkSmartPointer<vtkFloatArray>::New();
      layer.magnitude->SetName("displacement_mm");
      layer.magnitude->SetNumberOfTuples(static_cast<vtkIdType>(layer.embedded.points.size()));
      layer.magnitude->Fill(0);
      layer.data = triangles(layer.points, layer.triangles);
      layer.data->GetPointData()->SetScalars(layer.magnitude);
    }
    layer.stress = vtkSmartPointer<vtkFloatArray>::New();
    layer.stress->SetNumberOfTuples(static_cast<vtkIdType>(layer.triangles.size()));
    layer.stress->Fill(0);
    layer.data->GetCellData()->SetScalars(layer.stress);
    layer.normals = smooth_normals(layer.data);
    layer.mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    layer.mapper->SetInputConnection(layer.normals->GetOutputPort());
    layer.mapper->SetLookupTable(lookup_);
    layer.mapper->SetScalarModeToUsePointData();
    layer.actor = vtkSmartPointer<vtkActor>::New();
    layer.actor->SetMapper(layer.mapper);
    layer.actor->GetProperty()->BackfaceCullingOff();
    // A region on the outer surface draws its inner side as see-through as its outer one.
    if (outside.count(layer.material)) see_through(layer.actor);
    renderer_->AddActor(layer.actor);
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
  for (RegionLayer& layer : layers_) {  // smooth surfaces: each point moves with its element (affine for P1)
    const LabelSurface& e = layer.embedded;
    if (e.points.empty()) continue;
    for (std::size_t i = 0; i < e.points.size(); ++i) {
      double p[3] = {e.points[i][0], e.points[i][1], e.points[i][2]};
      float u[3] = {0, 0, 0};
      if (moved)
        for (int c = 0; c < 4; ++c) {
          const float* node = &s.displacement[3 * std::size_t(mesh_.tetrahedra[e.tetrahedron[i]][std::size_t(c)])];
          for (int d = 0; d < 3; ++d) u[d] += e.weights[i][std::size_t(c)] * node[d];
        }
      for (int d = 0; d < 3; ++d) p[d] += u[d];
      layer.points->SetPoint(static_cast<vtkIdType>(i), p);
      layer.magnitude->SetValue(static_cast<vtkIdType>(i), 1e3f * std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
    }
    layer.points->Modified();
    layer.magnitude->Modified();
  }
  const bool stress = field == ColourField::von_mises && s.von_mises.size() == mesh_.cells;
  if (stress) {
    float top = 0;
    const auto kpa_of = [&](unsigned int cell) {
      const float kpa = 1e-3f * static_cast<float>(s.von_mises[cell]);
      top = std::max(top, kpa);
      return kpa;
    };
    for (std::size_t t = 0; t < mesh_.boundary_triangle_cell.size(); ++t)
      stress_->SetValue(static_cast<vtkIdType>(t), kpa_of(mesh_.boundary_triangle_cell[t]));
    stress_->Modified();
    for (RegionLayer& layer : layers_) {
      for (std::size_t t = 0; t < layer.cells.size(); ++t) layer.stress->SetValue(static_cast<vtkIdType>(t), kpa_of(layer.cells[t]));
      layer.stress->Modified();
    }
    largest = top;
  }
  const bool cells = stress;
  const bool regions = field == ColourField::regions;
  field_ = field;
  std::vector<vtkPolyDataMapper*> mappers{surface_mapper_.Get()};
  for (RegionLayer& layer : layers_) mappers.push_back(layer.mapper.Get());
  if (regions) {
    surface_actor_->GetProperty()->SetColor(kSkin[0], kSkin[1], kSkin[2]);
    for (std::size_t i = 0; i < layers_.size(); ++i) {
      const std::array<double, 3> c = region_colour(i);
      layers_[i].actor->GetProperty()->SetColor(c[0], c[1], c[2]);
    }
  }
  bar_->SetVisibility(bar_wanted_ && !regions);
  for (auto* mapper : mappers) {
    mapper->SetScalarVisibility(!regions);
    if (cells)
      mapper->SetScalarModeToUseCellData();
    else
      mapper->SetScalarModeToUsePointData();
    // A range that never collapses: at rest the colours stay blue.
    mapper->SetScalarRange(0, std::max(largest, cells ? 0.1f : 0.5f));
  }
  bar_->SetTitle(cells ? "von Mises (kPa)" : "|u| (mm)");
  surface_->Modified();
  for (RegionLayer& layer : layers_) layer.data->Modified();
}

void TissueView::set_region_visible(std::size_t i, bool on) {
  if (i < layers_.size()) layers_[i].actor->SetVisibility(on);
}

bool TissueView::region_visible(std::size_t i) const { return i < layers_.size() && layers_[i].actor->GetVisibility(); }

vtkPolyData* TissueView::drawn_region(std::size_t i) {
  if (i >= layers_.size()) return nullptr;
  layers_[i].normals->Update();
  return layers_[i].normals->GetOutput();
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

void TissueView::show_colour_bar(bool on) {
  bar_wanted_ = on;
  bar_->SetVisibility(on && field_ != ColourField::regions);
}

std::array<double, 3> TissueView::region_colour(std::size_t i) const {
  // The wall skin-toned; then bone, flesh, and distinct hues for any further regions.
  static constexpr std::array<std::array<double, 3>, 6> kPalette{
      {{0.95, 0.90, 0.72}, {0.86, 0.50, 0.46}, {0.45, 0.70, 0.92}, {0.62, 0.84, 0.50}, {0.80, 0.62, 0.90}, {0.95, 0.70, 0.30}}};
  if (i < layers_.size() && layers_[i].name == "wall") return kSkin;
  std::size_t k = 0;
  for (std::size_t j = 0; j < i && j < layers_.size(); ++j) k += layers_[j].name != "wall";
  return kPalette[k % kPalette.size()];
}

void TissueView::reset_camera() {
  renderer_->ResetCamera(surface_->GetBounds());
  renderer_->GetActiveCamera()->Zoom(1.1);
}

}  // namespace fetouch::app::trainer
