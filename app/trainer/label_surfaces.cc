#include "app/trainer/label_surfaces.h"

#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "app/scene_mesh.h"
#include "imaging/volume_io.h"
#include "meshes/surface_extraction.h"
#include "meshes/tet_geometry.h"

namespace fetouch::app::trainer {

namespace {

using Point = std::array<double, 3>;

// The boundary of the voxels whose label is in `in` (index space scaled by the spacing: x = i *
// spacing), contoured from the indicator smoothed at sigma_mm and decimated towards triangle_mm.
vtkSmartPointer<vtkPolyData> contour(const imaging::Volume<std::uint8_t>& labels, const std::array<bool, 256>& in,
                                     const LabelSurfaceSettings& s) {
  const auto& n = labels.dimensions;
  std::array<int, 3> lo{n[0], n[1], n[2]}, hi{-1, -1, -1};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (in[labels.data[labels.index(i, j, k)]]) {
          const int at[3] = {i, j, k};
          for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], at[d]), hi[d] = std::max(hi[d], at[d]);
        }
  if (hi[0] < 0) return nullptr;
  // The region's box, grown by the Gaussian's reach and a layer of zeros so that the surface closes.
  std::array<int, 3> pad{}, size{};
  std::array<double, 3> sigma{};
  for (int d = 0; d < 3; ++d) {
    sigma[d] = s.smoothing_mm / labels.spacing_mm[d];
    pad[d] = static_cast<int>(std::ceil(2 * sigma[d])) + 2;
    size[d] = hi[d] - lo[d] + 1 + 2 * pad[d];
  }
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(size.data());
  image->SetSpacing(labels.spacing_mm.data());
  image->SetOrigin((lo[0] - pad[0]) * labels.spacing_mm[0], (lo[1] - pad[1]) * labels.spacing_mm[1],
                   (lo[2] - pad[2]) * labels.spacing_mm[2]);
  auto values = vtkSmartPointer<vtkFloatArray>::New();
  values->SetNumberOfTuples(image->GetNumberOfPoints());
  values->Fill(0);
  // The triangles' size: settings.triangle_mm, larger where the surface would otherwise need more
  // than max_triangles (its area estimated as a voxel face per voxel on its border: about 1.1 to 1.3
  // times a smooth surface's).
  long border = 0;
  const auto outside = [&](int i, int j, int k) {
    return i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2] || !in[labels.data[labels.index(i, j, k)]];
  };
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        if (in[labels.data[labels.index(i, j, k)]]) {
          int at[3] = {i - lo[0] + pad[0], j - lo[1] + pad[1], k - lo[2] + pad[2]};
          values->SetValue(image->ComputePointId(at), 1.0f);
          border += outside(i - 1, j, k) || outside(i + 1, j, k) || outside(i, j - 1, k) || outside(i, j + 1, k) ||
                    outside(i, j, k - 1) || outside(i, j, k + 1);
        }
  image->GetPointData()->SetScalars(values);
  const double area_mm2 = double(border) * std::pow(labels.voxel_volume_mm3(), 2.0 / 3.0);
  const double triangle_mm = std::max(s.triangle_mm, std::sqrt(area_mm2 / (s.max_triangles * std::sqrt(3.0) / 4)));
  std::array<double, 3> magnify{};  // the indicator contoured on a grid of half the triangles' size
  for (int d = 0; d < 3; ++d) magnify[d] = std::min(1.0, labels.spacing_mm[d] / (triangle_mm / 2));
  const vtkSmartPointer<vtkPolyData> extracted = meshes::blurred_level_set(image, sigma, magnify, /*largest_only=*/false);
  if (extracted->GetNumberOfPolys() == 0) return nullptr;
  const vtkSmartPointer<vtkPolyData> surface = meshes::smoothed_surface(extracted, 20);
  return meshes::decimated_towards(surface, triangle_mm, 100);
}

}  // namespace

std::vector<LabelSurface> label_surfaces(const imaging::Volume<std::uint8_t>& labels,
                                         const std::vector<std::pair<std::string, std::vector<int>>>& regions,
                                         const MeshView& mesh, const LabelSurfaceSettings& settings) {
  // Label -> material, through the region names MeshView and the scene share.
  constexpr unsigned int kNone = std::numeric_limits<unsigned int>::max();
  std::array<unsigned int, 256> material_of;
  material_of.fill(kNone);
  std::vector<std::pair<unsigned int, std::array<bool, 256>>> wanted;
  for (const auto& [id, name] : mesh.region_name)
    for (const auto& [region, values] : regions) {
      if (region != name) continue;
      std::array<bool, 256> in{};
      for (int v : values)
        if (v >= 0 && v < 256) in[std::size_t(v)] = true, material_of[std::size_t(v)] = id;
      wanted.emplace_back(id, in);
    }
  // Which region draws an interface: the smaller (by voxels), as TissueView draws mesh faces.
  std::map<unsigned int, double> volume;
  for (const std::uint8_t v : labels.data)
    if (material_of[v] != kNone) volume[material_of[v]] += 1;
  const auto owns = [&](unsigned int m, unsigned int other) {
    return volume[m] < volume[other] || (volume[m] == volume[other] && m > other);
  };
  const auto label_at = [&](const Point& x) -> int {  // x in index space scaled by the spacing
    int at[3];
    for (int d = 0; d < 3; ++d) {
      at[d] = static_cast<int>(std::lround(x[d] / labels.spacing_mm[d]));
      if (at[d] < 0 || at[d] >= labels.dimensions[d]) return 0;
    }
    return labels.data[labels.index(at[0], at[1], at[2])];
  };
  const double step = *std::min_element(labels.spacing_mm.begin(), labels.spacing_mm.end());

  std::vector<LabelSurface> out;
  for (const auto& [material, in] : wanted) {
    vtkSmartPointer<vtkPolyData> surface = contour(labels, in, settings);
    if (!surface) continue;
    const vtkIdType np = surface->GetNumberOfPoints();
    std::vector<Point> aligned(static_cast<std::size_t>(np));
    for (vtkIdType i = 0; i < np; ++i) surface->GetPoint(i, aligned[std::size_t(i)].data());
    struct Face {
      std::array<unsigned int, 3> v;
      Point centre, normal;
    };
    std::vector<Face> faces;
    auto ids = vtkSmartPointer<vtkIdList>::New();
    vtkCellArray* polys = surface->GetPolys();
    polys->InitTraversal();
    while (polys->GetNextCell(ids)) {
      if (ids->GetNumberOfIds() != 3) continue;
      Face f;
      for (int c = 0; c < 3; ++c) f.v[c] = static_cast<unsigned int>(ids->GetId(c));
      const Point &a = aligned[f.v[0]], &b = aligned[f.v[1]], &c = aligned[f.v[2]];
      const Point e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      f.normal = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
      const double length = std::hypot(f.normal[0], f.normal[1], f.normal[2]);
      if (!(length > 0)) continue;
      for (int d = 0; d < 3; ++d) f.normal[d] /= length, f.centre[d] = (a[d] + b[d] + c[d]) / 3;
      faces.push_back(f);
    }
    // Flying edges orients every triangle alike; which way, the labels on either side say (a vote,
    // since a triangle of a thin part can have the region on both sides of it).
    long outward = 0;
    const auto sample = [&](const Face& f, double along) {
      return label_at({f.centre[0] + along * f.normal[0], f.centre[1] + along * f.normal[1], f.centre[2] + along * f.normal[2]});
    };
    for (const Face& f : faces) {
      const bool plus = in[std::size_t(sample(f, step))], minus = in[std::size_t(sample(f, -step))];
      outward += (minus && !plus) - (plus && !minus);
    }
    const double sign = outward >= 0 ? 1 : -1;
    LabelSurface drawn;
    drawn.material = material;
    std::vector<unsigned int> renumber(aligned.size(), kNone);
    for (Face& f : faces) {
      if (sign < 0) std::swap(f.v[1], f.v[2]);
      // The region across: the first label outside this one along the outward normal.
      unsigned int across = material;
      for (const double along : {1.0, 1.5, 2.5, 3.5}) {
        const int l = sample(f, sign * along * step);
        if (!in[std::size_t(l)]) {
          across = material_of[std::size_t(l)];
          break;
        }
      }
      // Not drawn: the outer surface (the mesh draws it), an interface the other region draws, and a
      // triangle with this region on both sides (a fold where the region is thinner than the grid).
      if (across == kNone || across == material || !owns(material, across)) continue;
      std::array<unsigned int, 3> t{};
      for (int c = 0; c < 3; ++c) {
        unsigned int& to = renumber[f.v[c]];
        if (to == kNone) {
          to = static_cast<unsigned int>(drawn.points.size());
          // Into space: the index axes along the direction cosines about the origin, in metres.
          Point x{};
          for (int r = 0; r < 3; ++r) {
            x[r] = labels.origin_mm[r];
            for (int d = 0; d < 3; ++d) x[r] += labels.direction[3 * r + d] * aligned[f.v[c]][d];
            x[r] *= 1e-3;
          }
          drawn.points.push_back(x);
        }
        t[c] = to;
      }
      drawn.triangles.push_back(t);
      drawn.across.push_back(across);
    }
    if (drawn.triangles.empty()) continue;
    embed_points(mesh, drawn.points, drawn.tetrahedron, drawn.weights);
    out.push_back(std::move(drawn));
  }
  std::sort(out.begin(), out.end(), [](const LabelSurface& x, const LabelSurface& y) { return x.material < y.material; });
  return out;
}

std::optional<imaging::Volume<std::uint8_t>> scene_label_map(const config::Scene& scene) {
  const config::MeshingOptions& m = scene.mesh.meshing;
  if (m.regions.empty() || m.regions_from_image || m.surface == config::MeshSurface::conforming) return std::nullopt;
  if (scene.mesh.source == config::MeshSource::phantom) {
    imaging::PhantomSettings p = phantom_settings(scene.mesh.phantom);
    p.speckle = false;  // the labels only, as the mesher takes them
    return imaging::make_phantom(p).labels;
  }
  if (scene.mesh.source != config::MeshSource::volume) return std::nullopt;
  imaging::Volume<float> volume;
  try {
    volume = imaging::read_volume(scene.mesh.path);
  } catch (const std::exception& e) {
    throw std::runtime_error(scene.mesh.path.string() + ": " + e.what());
  }
  meshes::MaskVolume map = label_map(volume);  // as the mesher reads it
  imaging::Volume<std::uint8_t> labels;
  labels.dimensions = map.dimensions, labels.spacing_mm = map.spacing_mm;
  labels.origin_mm = map.origin_mm, labels.direction = map.direction;
  labels.data = std::move(map.data);
  return labels;
}

const std::vector<LabelSurface>& scene_label_surfaces(const config::Scene& scene, const MeshView& mesh,
                                                      LabelSurfaceCache& cache, double& made_s) {
  made_s = -1;
  double coordinates = 0;
  for (const auto& x : mesh.points) coordinates += x[0] + 2 * x[1] + 3 * x[2];
  std::ostringstream key;
  key.precision(17);
  key << scene.source.string() << ' ' << mesh.points.size() << ' ' << mesh.tetrahedra.size() << ' ' << coordinates;
  if (key.str() == cache.key) return cache.surfaces;
  const auto start = std::chrono::steady_clock::now();
  cache.key = key.str();
  cache.surfaces.clear();
  if (const auto labels = scene_label_map(scene)) cache.surfaces = label_surfaces(*labels, scene.mesh.meshing.regions, mesh);
  made_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return cache.surfaces;
}

void embed_points(const MeshView& mesh, const std::vector<std::array<double, 3>>& points,
                  std::vector<unsigned int>& tetrahedron, std::vector<std::array<float, 4>>& weights) {
  tetrahedron.assign(points.size(), 0);
  weights.assign(points.size(), {1, 0, 0, 0});
  if (mesh.tetrahedra.empty()) return;
  // A grid of boxes about the size of an element, each listing the tetrahedra whose bounding box
  // meets it.
  Point low = mesh.points[0], high = low;
  for (const Point& p : mesh.points)
    for (int d = 0; d < 3; ++d) low[d] = std::min(low[d], p[d]), high[d] = std::max(high[d], p[d]);
  double volume = 0;
  for (const auto& t : mesh.tetrahedra)
    volume += std::abs(meshes::tet_signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]));
  const double box = std::max(1e-6, 2 * std::cbrt(volume / double(mesh.tetrahedra.size())));
  std::array<int, 3> cells{};
  for (int d = 0; d < 3; ++d) cells[d] = std::max(1, static_cast<int>(std::ceil((high[d] - low[d]) / box)));
  const auto cell_of = [&](double x, int d) { return std::clamp(static_cast<int>((x - low[d]) / box), 0, cells[d] - 1); };
  std::vector<std::vector<unsigned int>> grid(static_cast<std::size_t>(cells[0]) * cells[1] * cells[2]);
  const auto slot = [&](int i, int j, int k) -> std::vector<unsigned int>& {
    return grid[(std::size_t(k) * cells[1] + j) * cells[0] + i];
  };
  for (unsigned int t = 0; t < mesh.tetrahedra.size(); ++t) {
    std::array<int, 3> a{}, b{};
    for (int d = 0; d < 3; ++d) {
      double lo = mesh.points[mesh.tetrahedra[t][0]][d], hi = lo;
      for (unsigned int v : mesh.tetrahedra[t]) lo = std::min(lo, mesh.points[v][d]), hi = std::max(hi, mesh.points[v][d]);
      a[d] = cell_of(lo, d), b[d] = cell_of(hi, d);
    }
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) slot(i, j, k).push_back(t);
  }
  // Barycentric coordinates of x in tetrahedron t (the smallest of them: >= 0 inside).
  const auto barycentric = [&](unsigned int t, const Point& x, std::array<double, 4>& w) {
    const auto& v = mesh.tetrahedra[t];
    const double whole = meshes::tet_signed_volume(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]);
    if (whole == 0) return -std::numeric_limits<double>::infinity();
    const std::array<Point, 4> corners{mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]};
    for (std::size_t c = 0; c < 4; ++c) {  // the volume with corner c moved to x, over the whole
      std::array<Point, 4> moved = corners;
      moved[c] = x;
      w[c] = meshes::tet_signed_volume(moved[0], moved[1], moved[2], moved[3]) / whole;
    }
    return *std::min_element(w.begin(), w.end());
  };
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Point& x = points[p];
    const std::array<int, 3> at{cell_of(x[0], 0), cell_of(x[1], 1), cell_of(x[2], 2)};
    double best = -std::numeric_limits<double>::infinity();
    std::array<double, 4> w{}, best_w{1, 0, 0, 0};
    // The box that holds x first; outside the mesh (or on its border) the boxes around it too.
    for (int reach = 0; reach <= 2 && best < -1e-9; ++reach)
      for (int k = at[2] - reach; k <= at[2] + reach; ++k)
        for (int j = at[1] - reach; j <= at[1] + reach; ++j)
          for (int i = at[0] - reach; i <= at[0] + reach; ++i) {
            if (i < 0 || j < 0 || k < 0 || i >= cells[0] || j >= cells[1] || k >= cells[2]) continue;
            if (std::max({std::abs(i - at[0]), std::abs(j - at[1]), std::abs(k - at[2])}) != reach) continue;
            for (unsigned int t : slot(i, j, k)) {
              const double least = barycentric(t, x, w);
              if (least > best) best = least, best_w = w, tetrahedron[p] = t;
            }
          }
    if (best == -std::numeric_limits<double>::infinity())  // far from every element: the nearest by coordinates
      for (unsigned int t = 0; t < mesh.tetrahedra.size(); ++t) {
        const double least = barycentric(t, x, w);
        if (least > best) best = least, best_w = w, tetrahedron[p] = t;
      }
    for (int c = 0; c < 4; ++c) weights[p][std::size_t(c)] = static_cast<float>(best_w[std::size_t(c)]);
  }
}

}  // namespace fetouch::app::trainer
