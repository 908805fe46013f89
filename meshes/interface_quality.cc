#include "meshes/interface_quality.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace fetouch::meshes {

namespace {

Point3 unit_normal(const std::vector<Point3>& p, const std::array<int, 3>& t) {
  const Point3 &a = p[std::size_t(t[0])], &b = p[std::size_t(t[1])], &c = p[std::size_t(t[2])];
  const Point3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  Point3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (length > 0)
    for (double& x : n) x /= length;
  return n;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const std::size_t at = std::min(values.size() - 1, static_cast<std::size_t>(q * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + long(at), values.end());
  return values[at];
}

// The label boundary between side `a` and side `b` (region indices; -1: no region, or outside the
// grid), searched within kWindow voxels of a point.
constexpr int kWindow = 4;

struct LabelBoundary {
  const MaskVolume& labels;
  std::array<int, 256> region_of_label{};
  int region(long i, long j, long k) const {
    if (i < 0 || j < 0 || k < 0 || i >= labels.dimensions[0] || j >= labels.dimensions[1] || k >= labels.dimensions[2]) return -1;
    return region_of_label[labels.data[std::size_t((k * labels.dimensions[1] + j) * labels.dimensions[0] + i)]];
  }
  // Millimetres from a point (metres, in space) to the nearest voxel face with `a` on one side and
  // `b` on the other; kWindow voxels' worth when there is none that near.
  double distance_mm(const Point3& x_m, int a, int b) const {
    double t[3];
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (int r = 0; r < 3; ++r) s += labels.direction[std::size_t(3 * r + c)] * (x_m[std::size_t(r)] * 1e3 - labels.origin_mm[std::size_t(r)]);
      t[c] = s / labels.spacing_mm[std::size_t(c)];
    }
    const auto& h = labels.spacing_mm;
    double best2 = std::pow(kWindow * *std::max_element(h.begin(), h.end()), 2);
    const long ci = std::lround(t[0]), cj = std::lround(t[1]), ck = std::lround(t[2]);
    for (long k = ck - kWindow; k <= ck + kWindow; ++k)
      for (long j = cj - kWindow; j <= cj + kWindow; ++j)
        for (long i = ci - kWindow; i <= ci + kWindow; ++i) {
          if (region(i, j, k) != a) continue;
          const long v[3] = {i, j, k};
          for (int axis = 0; axis < 3; ++axis)
            for (int step = -1; step <= 1; step += 2) {
              long w[3] = {i, j, k};
              w[axis] += step;
              if (region(w[0], w[1], w[2]) != b) continue;
              double d2 = 0;
              for (int c = 0; c < 3; ++c) {
                const double gap = c == axis ? std::abs(t[c] - (double(v[c]) + 0.5 * step))
                                             : std::max(0.0, std::abs(t[c] - double(v[c])) - 0.5);
                d2 += gap * gap * h[std::size_t(c)] * h[std::size_t(c)];
              }
              best2 = std::min(best2, d2);
            }
        }
    return std::sqrt(best2);
  }
};

}  // namespace

std::vector<double> neighbour_normal_angles_deg(const std::vector<Point3>& nodes, const std::vector<std::array<int, 3>>& triangles) {
  std::map<std::array<int, 2>, std::vector<int>> edges;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      std::array<int, 2> edge{triangles[t][std::size_t(e)], triangles[t][std::size_t((e + 1) % 3)]};
      if (edge[0] > edge[1]) std::swap(edge[0], edge[1]);
      edges[edge].push_back(static_cast<int>(t));
    }
  std::vector<double> angles;
  for (const auto& [edge, around] : edges) {
    if (around.size() != 2) continue;
    const Point3 n = unit_normal(nodes, triangles[std::size_t(around[0])]), m = unit_normal(nodes, triangles[std::size_t(around[1])]);
    const double cosine = std::min(1.0, std::abs(n[0] * m[0] + n[1] * m[1] + n[2] * m[2]));
    angles.push_back(std::acos(cosine) * 180 / M_PI);
  }
  return angles;
}

std::vector<VolumeMesh::SurfaceReport> surface_smoothness(const VolumeMesh& mesh, const MaskVolume& labels,
                                                          const std::vector<MeshRegion>& regions) {
  // The surfaces: (lower side, higher side) -> triangles; -1 the outside.
  std::map<std::array<int, 2>, std::vector<std::array<int, 3>>> groups;
  const bool by_region = !mesh.region.empty();
  for (std::size_t b = 0; b < mesh.boundary.size(); ++b)
    groups[{by_region && b < mesh.boundary_region.size() ? mesh.boundary_region[b] : 0, -1}].push_back(mesh.boundary[b]);
  for (std::size_t f = 0; f < mesh.interfaces.size(); ++f) groups[mesh.interface_regions[f]].push_back(mesh.interfaces[f]);

  LabelBoundary boundary{labels};
  boundary.region_of_label.fill(-1);
  if (regions.empty())
    for (int l = 1; l < 256; ++l) boundary.region_of_label[std::size_t(l)] = 0;
  for (std::size_t r = 0; r < regions.size(); ++r)
    for (int l : regions[r].labels) boundary.region_of_label[std::size_t(l)] = static_cast<int>(r);
  const bool measure = !labels.data.empty();

  std::vector<VolumeMesh::SurfaceReport> out;
  for (const auto& group : groups) {
    // Named references, not a structured binding: C++17 lambdas cannot capture bindings (clang refuses).
    const auto& sides = group.first;
    const auto& triangles = group.second;
    VolumeMesh::SurfaceReport report;
    const auto name = [&](int r) {
      return r < 0 ? std::string("outside") : r < int(mesh.region_names.size()) ? mesh.region_names[std::size_t(r)] : "tissue";
    };
    report.name = !by_region ? "outside" : sides[1] < 0 ? name(sides[0]) + "_outside" : name(sides[0]) + "_" + name(sides[1]);
    report.triangles = static_cast<long>(triangles.size());
    const std::vector<double> angles = neighbour_normal_angles_deg(mesh.nodes_m, triangles);
    report.median_angle_deg = quantile(angles, 0.5);
    report.p99_angle_deg = quantile(angles, 0.99);
    report.max_angle_deg = angles.empty() ? 0 : *std::max_element(angles.begin(), angles.end());
    if (measure) {
      report.max_distance_mm = 0;
      const auto& p = mesh.nodes_m;
      const auto farther = [&](const Point3& x) {
        report.max_distance_mm = std::max(report.max_distance_mm, boundary.distance_mm(x, sides[0], sides[1]));
      };
      std::set<int> nodes;  // each node once, however many triangles share it
      for (const auto& t : triangles) nodes.insert(t.begin(), t.end());
      for (int v : nodes) farther(p[std::size_t(v)]);
      for (const auto& t : triangles) {
        const Point3 &a = p[std::size_t(t[0])], &b = p[std::size_t(t[1])], &c = p[std::size_t(t[2])];
        const auto mix = [](const Point3& x, const Point3& y, const Point3& z, double wx, double wy, double wz) {
          return Point3{wx * x[0] + wy * y[0] + wz * z[0], wx * x[1] + wy * y[1] + wz * z[1], wx * x[2] + wy * y[2] + wz * z[2]};
        };
        for (const Point3& x : {mix(a, b, c, 0.5, 0.5, 0), mix(a, b, c, 0, 0.5, 0.5), mix(a, b, c, 0.5, 0, 0.5),
                                mix(a, b, c, 1 / 3.0, 1 / 3.0, 1 / 3.0)})
          farther(x);
      }
    }
    out.push_back(report);
  }
  return out;
}

}  // namespace fetouch::meshes
