// Which faces of a tetrahedral mesh are its boundary, whether that boundary is a closed
// 2-manifold, and moving it out to a volume (meshes/tet_repair.h declares them).
#include "meshes/tet_repair.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace fetouch::meshes {

namespace {

constexpr auto& kFace = kTetFace;

// How many elements hold each element's face (index 4 t + f, the face opposite vertex f): 1 on the
// boundary, 2 inside, more where the mesh is not a manifold. Found through the elements around
// each node (no map of all faces: a head at 2 mm has sixteen million).
std::vector<int> face_multiplicity(const std::vector<Tet>& tets) {
  int nodes = 0;
  for (const Tet& t : tets) nodes = std::max(nodes, 1 + *std::max_element(t.begin(), t.end()));
  std::vector<int> first(std::size_t(nodes) + 1, 0), star(4 * tets.size());
  for (const Tet& t : tets)
    for (int v : t) ++first[std::size_t(v) + 1];
  for (int v = 0; v < nodes; ++v) first[std::size_t(v) + 1] += first[std::size_t(v)];
  std::vector<int> fill(first.begin(), first.end() - 1);
  for (int t = 0; t < static_cast<int>(tets.size()); ++t)
    for (int v : tets[t]) star[std::size_t(fill[std::size_t(v)]++)] = t;
  std::vector<int> count(4 * tets.size(), 0);
  const auto holds = [](const Tet& t, int v) { return t[0] == v || t[1] == v || t[2] == v || t[3] == v; };
  for (int t = 0; t < static_cast<int>(tets.size()); ++t)
    for (int f = 0; f < 4; ++f) {
      if (count[4 * std::size_t(t) + f] != 0) continue;  // counted from an element across it
      const int a = tets[t][kFace[f][0]], b = tets[t][kFace[f][1]], c = tets[t][kFace[f][2]];
      int n = 0;
      for (int k = first[std::size_t(a)]; k < first[std::size_t(a) + 1]; ++k)
        n += holds(tets[star[std::size_t(k)]], b) && holds(tets[star[std::size_t(k)]], c);
      for (int k = first[std::size_t(a)]; k < first[std::size_t(a) + 1]; ++k) {
        const int u = star[std::size_t(k)];
        if (!holds(tets[u], b) || !holds(tets[u], c)) continue;
        for (int g = 0; g < 4; ++g)
          if (tets[u][g] != a && tets[u][g] != b && tets[u][g] != c) count[4 * std::size_t(u) + g] = n;
      }
    }
  return count;
}

std::vector<Triangle> faces_held_once(const std::vector<Tet>& tets, const std::vector<int>& count) {
  std::vector<Triangle> out;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int f = 0; f < 4; ++f)
      if (count[4 * t + f] == 1) out.push_back({tets[t][kFace[f][0]], tets[t][kFace[f][1]], tets[t][kFace[f][2]]});
  return out;
}

}  // namespace

std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets) {
  return faces_held_once(tets, face_multiplicity(tets));
}

namespace {

// Each boundary node's link: the edges opposite it in its boundary faces. Closed and manifold
// when every boundary edge has two faces and every link is one cycle.
bool closed_manifold_surface(const std::vector<Triangle>& boundary) {
  std::map<std::pair<int, int>, int> edges;
  std::map<int, std::vector<std::pair<int, int>>> links;
  for (const Triangle& f : boundary) {
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
      links[a].push_back({b, c});
    }
  }
  for (const auto& [e, faces] : edges)
    if (faces != 2) return false;
  for (auto& [v, link] : links) {
    // Walk the cycle from the first edge; it must visit every edge of the link.
    std::size_t visited = 1;
    int previous = link[0].first, current = link[0].second;
    while (current != link[0].first && visited <= link.size()) {
      int next = -1;
      for (const auto& [x, y] : link)
        if (x == current && y != previous) next = y;
        else if (y == current && x != previous) next = x;
      if (next < 0) return false;
      previous = current, current = next, ++visited;
    }
    if (visited != link.size()) return false;
  }
  return true;
}

}  // namespace

bool boundary_is_closed_manifold(const std::vector<Tet>& tets) {
  bool closed_manifold = false;
  boundary_faces(tets, &closed_manifold);
  return closed_manifold;
}

std::vector<Triangle> boundary_faces(const std::vector<Tet>& tets, bool* closed_manifold) {
  const std::vector<int> count = face_multiplicity(tets);
  std::vector<Triangle> boundary = faces_held_once(tets, count);
  *closed_manifold = std::none_of(count.begin(), count.end(), [](int n) { return n > 2; }) &&
                     closed_manifold_surface(boundary);
  return boundary;
}

using namespace tet_math;

double restore_volume(std::vector<Point3>& nodes, const std::vector<Tet>& tets, double target_volume, double max_offset,
                      double floor_deg) {
  const auto volume_of = [&](const std::vector<Point3>& at) {
    double v = 0;
    for (const Tet& t : tets) v += tet_signed_volume(at[t[0]], at[t[1]], at[t[2]], at[t[3]]);
    return v;
  };
  // Each boundary node's normal: the sum of its outward faces' area vectors, made unit. Moving
  // every boundary node by d along it changes the volume by about d times the boundary's area.
  std::vector<Point3> normal(nodes.size(), Point3{0, 0, 0});
  std::vector<char> moving(nodes.size(), 0);
  double area = 0;
  for (const Triangle& f : boundary_faces(tets)) {
    const Point3 &a = nodes[f[0]], &b = nodes[f[1]], &c = nodes[f[2]];
    const Point3 n = cross(sub(b, a), sub(c, a));  // twice the area vector
    area += 0.5 * norm(n);
    for (const int v : f) {
      moving[v] = 1;
      for (int k = 0; k < 3; ++k) normal[v][k] += n[k];
    }
  }
  if (area <= 0 || !(target_volume > 0)) return 0;
  for (std::size_t v = 0; v < nodes.size(); ++v) {
    const double length = norm(normal[v]);
    for (int k = 0; k < 3; ++k) normal[v][k] = length > 0 ? normal[v][k] / length : 0;
  }
  std::vector<Point3> moved = nodes;
  const auto move_by = [&](double d) {
    for (std::size_t v = 0; v < nodes.size(); ++v)
      if (moving[v])
        for (int k = 0; k < 3; ++k) moved[v][k] = nodes[v][k] + d * normal[v][k];
    return volume_of(moved);
  };
  // Secant steps on the offset, the first with the boundary's area as the slope.
  double offset = 0, volume = volume_of(nodes), slope = area;
  for (int step = 0; step < 20 && std::abs(volume - target_volume) > 1e-12 * target_volume; ++step) {
    const double next = std::clamp(offset + (target_volume - volume) / slope, -max_offset, max_offset);
    if (next == offset) break;  // held at the bound
    const double next_volume = move_by(next);
    if (next_volume != volume) slope = (next_volume - volume) / (next - offset);
    offset = next, volume = next_volume;
    if (!(slope > 0)) return 0;
  }
  move_by(offset);
  for (const Tet& t : tets) {
    if (!moving[t[0]] && !moving[t[1]] && !moving[t[2]] && !moving[t[3]]) continue;  // unchanged
    const double before = min_dihedral_deg(nodes, t), after = min_dihedral_deg(moved, t);
    if (after <= 0 || (after < floor_deg && after < before)) return 0;
  }
  nodes = std::move(moved);
  return offset;
}

}  // namespace fetouch::meshes
