// Which faces of a tetrahedral mesh are its boundary, and whether that boundary is a closed
// 2-manifold (meshes/tet_repair.h declares them).
#include "meshes/tet_repair.h"

#include <algorithm>
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

}  // namespace fetouch::meshes
