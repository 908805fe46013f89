#include "meshes/tet_repair.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace fetouch::meshes {

namespace {

using namespace tet_math;
constexpr auto& kFace = kTetFace;

// A mesh being repaired: the elements (dead ones marked), and for each node the live elements
// that use it. Every adjacency question (is this face, edge or node on the boundary; which
// elements share this edge) is answered from those lists.
class RepairMesh {
 public:
  // `region`: each element's region (or null: one region); faces between regions are surfaces as
  // the boundary is (no flip crosses them, their nodes move only along them), and new elements take
  // the region of those they replace.
  RepairMesh(std::vector<Point3>& nodes, std::vector<Tet>& tets, std::vector<int>* region)
      : nodes_(nodes), tets_(tets), region_(region), alive_(tets.size(), true) {
    star_.resize(nodes.size());
    for (int t = 0; t < static_cast<int>(tets.size()); ++t)
      for (int v : tets[t]) star_[v].push_back(t);
  }

  double quality(int t) const { return min_dihedral_deg(nodes_, tets_[t]); }
  double quality(const std::vector<int>& ts) const {
    double q = 180;
    for (int t : ts) q = std::min(q, quality(t));
    return q;
  }
  bool alive(int t) const { return alive_[t]; }
  const Tet& tet(int t) const { return tets_[t]; }

  // The live elements holding all the given nodes.
  std::vector<int> sharing(std::initializer_list<int> vs) const {
    const auto first = vs.begin();
    std::vector<int> out;
    for (int t : star_[*first]) {
      bool all = true;
      for (auto v = first + 1; v != vs.end() && all; ++v) all = std::count(tets_[t].begin(), tets_[t].end(), *v) > 0;
      if (all) out.push_back(t);
    }
    return out;
  }
  // On the boundary or, with regions, on an interface between two.
  bool face_on_boundary(int a, int b, int c) const {
    const auto around = sharing({a, b, c});
    return around.size() == 1 || (region_ && around.size() == 2 && (*region_)[around[0]] != (*region_)[around[1]]);
  }
  bool face_outside(int a, int b, int c) const { return sharing({a, b, c}).size() == 1; }
  bool edge_on_boundary(int a, int b, bool outside_only = false) const {
    for (int t : sharing({a, b}))
      for (int c : tets_[t])
        if (c != a && c != b && (outside_only ? face_outside(a, b, c) : face_on_boundary(a, b, c))) return true;
    return false;
  }
  bool node_on_boundary(int v) const {
    for (int t : star_[v])
      for (int f = 0; f < 4; ++f)
        if (tets_[t][f] != v && face_on_boundary(tets_[t][kFace[f][0]], tets_[t][kFace[f][1]], tets_[t][kFace[f][2]]))
          return true;
    return false;
  }

  void kill(int t) {
    alive_[t] = false;
    for (int v : tets_[t]) star_[v].erase(std::find(star_[v].begin(), star_[v].end(), t));
  }
  void add(Tet t, int region) {
    if (tet_signed_volume(nodes_[t[0]], nodes_[t[1]], nodes_[t[2]], nodes_[t[3]]) < 0) std::swap(t[2], t[3]);
    if (region_) region_->push_back(region);
    tets_.push_back(t);
    alive_.push_back(true);
    for (int v : t) star_[v].push_back(static_cast<int>(tets_.size()) - 1);
  }
  double volume(const Tet& t) const { return tet_signed_volume(nodes_[t[0]], nodes_[t[1]], nodes_[t[2]], nodes_[t[3]]); }
  double abs_volume(const Tet& t) const { return std::abs(volume(t)); }
  double quality_of(Tet t) const {
    if (volume(t) < 0) std::swap(t[2], t[3]);
    return min_dihedral_deg(nodes_, t);
  }

  // Replaces `old` by `fresh` if they fill the same space (the sum of volumes agrees, so the new
  // elements neither overlap nor reach outside) and the worst angle improves.
  bool replace(const std::vector<int>& old, const std::vector<Tet>& fresh) {
    double before = 0, after = 0;
    for (int t : old) before += volume(tets_[t]);
    for (const Tet& t : fresh) {
      const double v = abs_volume(t);
      if (!(v > 1e-9 * before)) return false;
      after += v;
    }
    if (std::abs(after - before) > 1e-9 * before) return false;
    double q_new = 180;
    for (const Tet& t : fresh) q_new = std::min(q_new, quality_of(t));
    if (!(q_new > quality(old) + 1e-6)) return false;
    const int region = region_ ? (*region_)[old.front()] : 0;
    for (int t : old) kill(t);
    for (const Tet& t : fresh) add(t, region);
    return true;
  }

  // A sliver with two or three faces on the boundary is cut away, when the boundary stays
  // manifold without it.
  bool peel(int t, double* volume_removed) {
    const Tet& e = tets_[t];
    std::array<bool, 4> outside{};
    int count = 0;
    for (int f = 0; f < 4; ++f) count += outside[f] = face_outside(e[kFace[f][0]], e[kFace[f][1]], e[kFace[f][2]]);
    if (count == 2) {
      // The two inner faces share the edge between the vertices opposite the two outer faces;
      // it becomes a boundary edge and must not be one already.
      int shared[2], k = 0;
      for (int f = 0; f < 4; ++f)
        if (outside[f]) shared[k++] = e[f];
      if (edge_on_boundary(shared[0], shared[1], true)) return false;
    } else if (count == 3) {
      // The apex (the vertex opposite the inner face) leaves the mesh with the element.
      int apex = -1;
      for (int f = 0; f < 4; ++f)
        if (!outside[f]) apex = e[f];
      if (star_[apex].size() != 1) return false;
    } else {
      return false;
    }
    *volume_removed += volume(e);
    kill(t);
    return true;
  }

  // 3-2: the three elements around an interior edge (a, b) become two on the triangle of the ring.
  bool flip32(int t, int* flips) {
    const Tet e = tets_[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const int a = e[i], b = e[j];
        const auto ring = sharing({a, b});
        if (ring.size() != 3 || edge_on_boundary(a, b)) continue;
        std::vector<int> others;
        for (int r : ring)
          for (int v : tets_[r])
            if (v != a && v != b && std::find(others.begin(), others.end(), v) == others.end()) others.push_back(v);
        if (others.size() != 3 || !sharing({others[0], others[1], others[2]}).empty()) continue;
        if (replace(ring, {{others[0], others[1], others[2], a}, {others[0], others[1], others[2], b}})) {
          ++*flips;
          return true;
        }
      }
    return false;
  }

  // 2-3: two elements sharing an interior face (a, b, c) become three around the edge between
  // their apexes.
  bool flip23(int t, int* flips) {
    const Tet e = tets_[t];
    for (int f = 0; f < 4; ++f) {
      const int a = e[kFace[f][0]], b = e[kFace[f][1]], c = e[kFace[f][2]], d = e[f];
      const auto pair = sharing({a, b, c});
      if (pair.size() != 2 || (region_ && (*region_)[pair[0]] != (*region_)[pair[1]])) continue;
      const int other = pair[0] == t ? pair[1] : pair[0];
      int apex = -1;
      for (int v : tets_[other])
        if (v != a && v != b && v != c) apex = v;
      if (!sharing({d, apex}).empty()) continue;
      if (replace({t, other}, {{a, b, d, apex}, {b, c, d, apex}, {c, a, d, apex}})) {
        ++*flips;
        return true;
      }
    }
    return false;
  }

  // 4-4: the four elements around an interior edge (a, b) become four around a diagonal of their
  // ring: the first of the two diagonals whose elements raise the worst angle.
  bool flip44(int t, int* flips) {
    const Tet e = tets_[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const int a = e[i], b = e[j];
        const auto ring = sharing({a, b});
        if (ring.size() != 4 || edge_on_boundary(a, b)) continue;
        const std::vector<int> cycle = ring_cycle(ring, a, b);
        if (cycle.size() != 4) continue;
        for (int d = 0; d < 2; ++d) {
          const int u = cycle[std::size_t(d)], w = cycle[std::size_t(d + 2)];
          const int x = cycle[std::size_t(d + 1)], y = cycle[std::size_t((d + 3) % 4)];
          if (!sharing({u, w}).empty()) continue;
          if (replace(ring, {{u, w, x, a}, {u, w, x, b}, {u, w, y, a}, {u, w, y, b}})) {
            ++*flips;
            return true;
          }
        }
      }
    return false;
  }

  // Edge removal (rings of 5 to 7 elements): the elements around an interior edge (a, b) become
  // two fans, to a and to b, over the triangulation of their ring whose worst element is best
  // (dynamic programming over the ring polygon's triangulations).
  bool remove_edge(int t, int* removals) {
    const Tet e = tets_[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const int a = e[i], b = e[j];
        const auto ring = sharing({a, b});
        const int n = static_cast<int>(ring.size());
        if (n < 5 || n > 7 || edge_on_boundary(a, b)) continue;
        std::vector<int> cycle = ring_cycle(ring, a, b);
        if (static_cast<int>(cycle.size()) != n) continue;
        // The orientation every new element over a must have (and the opposite over b).
        double fan = 0;
        for (int k = 1; k + 1 < n; ++k) fan += volume({cycle[0], cycle[std::size_t(k)], cycle[std::size_t(k + 1)], a});
        const double sign = fan >= 0 ? 1 : -1;
        const auto triangle_quality = [&](int p, int q, int r) {
          const Tet over_a{cycle[std::size_t(p)], cycle[std::size_t(q)], cycle[std::size_t(r)], a};
          const Tet over_b{cycle[std::size_t(p)], cycle[std::size_t(q)], cycle[std::size_t(r)], b};
          if (sign * volume(over_a) <= 0 || sign * volume(over_b) >= 0) return -1.0;
          return std::min(quality_of(over_a), quality_of(over_b));
        };
        // best[p][q]: the best worst angle over triangulations of the sub-polygon p..q; cut[p][q] its apex.
        double best[7][7] = {};
        int cut[7][7] = {};
        for (int span = 2; span < n; ++span)
          for (int p = 0; p + span < n; ++p) {
            const int q = p + span;
            best[p][q] = -1;
            for (int r = p + 1; r < q; ++r) {
              double v = triangle_quality(p, r, q);
              if (r - p > 1) v = std::min(v, best[p][r]);
              if (q - r > 1) v = std::min(v, best[r][q]);
              if (v > best[p][q]) best[p][q] = v, cut[p][q] = r;
            }
          }
        if (!(best[0][n - 1] > quality(ring) + 1e-6)) continue;
        std::vector<Tet> fresh;
        std::vector<std::pair<int, int>> todo{{0, n - 1}};
        while (!todo.empty()) {
          const auto [p, q] = todo.back();
          todo.pop_back();
          if (q - p < 2) continue;
          const int r = cut[p][q];
          const int u = cycle[std::size_t(p)], v = cycle[std::size_t(r)], w = cycle[std::size_t(q)];
          fresh.push_back({u, v, w, a});
          fresh.push_back({u, v, w, b});
          todo.push_back({p, r});
          todo.push_back({r, q});
        }
        if (replace(ring, fresh)) {
          ++*removals;
          return true;
        }
      }
    return false;
  }

  // The nodes of the ring around edge (a, b) in order (each element holds two neighbouring ones);
  // shorter than the ring if they do not close into one cycle.
  std::vector<int> ring_cycle(const std::vector<int>& ring, int a, int b) const {
    std::vector<std::array<int, 2>> links;
    for (int r : ring) {
      std::array<int, 2> l{-1, -1};
      int k = 0;
      for (int v : tets_[r])
        if (v != a && v != b && k < 2) l[std::size_t(k++)] = v;
      links.push_back(l);
    }
    std::vector<int> cycle{links[0][0], links[0][1]};
    std::vector<bool> used(links.size(), false);
    used[0] = true;
    while (cycle.size() < links.size()) {
      bool grown = false;
      for (std::size_t k = 0; k < links.size() && !grown; ++k)
        if (!used[k] && (links[k][0] == cycle.back() || links[k][1] == cycle.back())) {
          used[k] = true, grown = true;
          cycle.push_back(links[k][0] == cycle.back() ? links[k][1] : links[k][0]);
        }
      if (!grown) break;
    }
    return cycle;
  }

  // A flat element whose two faces lie on one interface (a cap on it): it changes sides, so the
  // interface takes its two other faces instead (an edge flip of the interface, which the element's
  // flatness keeps within its fold), and a flip within its new region then removes it or a node
  // move improves it. Undone if neither does.
  bool move_cap(int t, SliverRepair* report) {
    if (!region_) return false;
    const Tet e = tets_[t];
    const int own = (*region_)[t];
    int other_region = -1, count = 0;
    std::array<int, 2> on{};  // the faces (by opposite vertex) on the interface
    for (int f = 0; f < 4; ++f) {
      const auto around = sharing({e[kFace[f][0]], e[kFace[f][1]], e[kFace[f][2]]});
      if (around.size() != 2) return false;  // a face on the outer boundary: peeling's case
      const int r = (*region_)[around[0] == t ? around[1] : around[0]];
      if (r == own) continue;
      if (count == 2 || (other_region >= 0 && r != other_region)) return false;
      other_region = r, on[std::size_t(count++)] = f;
    }
    if (count != 2) return false;
    // Dihedral angles in dihedral_angles_deg's order of face pairs (0,1) (0,2) (0,3) (1,2) (1,3) (2,3).
    const auto pair_index = [](int f, int g) { return f == 0 ? g - 1 : f == 1 ? g + 1 : 5; };
    const auto angles = dihedral_angles_deg(nodes_[e[0]], nodes_[e[1]], nodes_[e[2]], nodes_[e[3]]);
    int rest[2], k = 0;
    for (int f = 0; f < 4; ++f)
      if (f != on[0] && f != on[1]) rest[k++] = f;
    // The old crease (between the two interface faces) and the new one (between the other two):
    // both within 30 degrees of flat.
    if (angles[std::size_t(pair_index(on[0], on[1]))] < 150 || angles[std::size_t(pair_index(rest[0], rest[1]))] < 150)
      return false;
    const int b = e[std::size_t(on[0])], d = e[std::size_t(on[1])];  // the new crease's ends
    if (edge_on_boundary(b, d)) return false;  // it would meet another surface
    (*region_)[t] = other_region;
    if (flip32(t, &report->flips32) || flip44(t, &report->flips44) || remove_edge(t, &report->edge_removals) ||
        flip23(t, &report->flips23) || relocate(t)) {
      ++report->caps_moved;
      return true;
    }
    (*region_)[t] = own;
    return false;
  }

  // A node of the element moves towards where each of its elements would be regular on its
  // opposite face, as far as improves the worst angle around it. A node on the boundary moves only
  // in the plane tangent to the surface there, and only where the surface around it is nearly flat
  // (its faces' normals within 25 degrees of their mean), so that the surface keeps its shape.
  bool relocate(int t) {
    for (int v : tets_[t]) {
      const std::vector<int> around = star_[v];
      Point3 normal{0, 0, 0};
      std::vector<Point3> face_normals;
      for (int s : around) {
        const Tet& e = tets_[s];
        for (int f = 0; f < 4; ++f) {
          const int a = e[kFace[f][0]], b = e[kFace[f][1]], c = e[kFace[f][2]];
          if (e[f] == v || !face_on_boundary(a, b, c)) continue;
          const Point3 n = cross(sub(nodes_[b], nodes_[a]), sub(nodes_[c], nodes_[a]));
          face_normals.push_back(n);
          for (int k = 0; k < 3; ++k) normal[k] += n[k];
        }
      }
      const bool on_boundary = !face_normals.empty();
      if (on_boundary) {
        const double length = norm(normal);
        for (double& c : normal) c /= length;
        bool flat = true;
        // Within 25 degrees of flat on a boundary; 10 where regions meet, whose interfaces a
        // trainee sees and whose smoothness the conforming mesher is for.
        const double flat_deg = region_ ? 10 : 25;
        for (const Point3& n : face_normals) flat = flat && dot(n, normal) > std::cos(flat_deg * M_PI / 180) * norm(n);
        if (!flat) continue;
      }
      Point3 target{0, 0, 0};
      for (int s : around) {
        const Tet& e = tets_[s];
        const int f = static_cast<int>(std::find(e.begin(), e.end(), v) - e.begin());
        const Point3 &p = nodes_[e[kFace[f][0]]], &q = nodes_[e[kFace[f][1]]], &r = nodes_[e[kFace[f][2]]];
        Point3 n = cross(sub(q, p), sub(r, p));  // points out of the element, away from v
        const double length = norm(n);
        const double edge = (norm(sub(q, p)) + norm(sub(r, q)) + norm(sub(p, r))) / 3;
        for (int k = 0; k < 3; ++k) target[k] += (p[k] + q[k] + r[k]) / 3 - n[k] / length * edge * std::sqrt(2.0 / 3);
      }
      const Point3 start = nodes_[v];
      Point3 move;
      for (int k = 0; k < 3; ++k) move[k] = target[k] / around.size() - start[k];
      if (on_boundary) {
        const double normal_part = dot(move, normal);
        for (int k = 0; k < 3; ++k) move[k] -= normal_part * normal[k];
      }
      const double q0 = quality(around);
      double best = q0;
      Point3 best_point = start;
      for (double step : {1.0, 0.5, 0.25, 0.125}) {
        for (int k = 0; k < 3; ++k) nodes_[v][k] = start[k] + step * move[k];
        const double q = quality(around);
        if (q > best) best = q, best_point = nodes_[v];
      }
      nodes_[v] = best_point;
      if (best > q0 + 1e-6) return true;
    }
    return false;
  }

  // Drops the dead elements and the nodes no element uses (the others keep their order).
  void compact() {
    std::vector<Tet> kept;
    std::vector<int> kept_region;
    std::vector<int> index(nodes_.size(), -1);
    for (std::size_t t = 0; t < tets_.size(); ++t)
      if (alive_[t]) {
        kept.push_back(tets_[t]);
        if (region_) kept_region.push_back((*region_)[t]);
        for (int v : tets_[t]) index[v] = 0;
      }
    std::vector<Point3> used;
    for (std::size_t v = 0; v < nodes_.size(); ++v)
      if (index[v] == 0) index[v] = static_cast<int>(used.size()), used.push_back(nodes_[v]);
    for (Tet& t : kept)
      for (int& v : t) v = index[v];
    tets_ = std::move(kept);
    nodes_ = std::move(used);
    if (region_) *region_ = std::move(kept_region);
  }

 private:
  std::vector<Point3>& nodes_;
  std::vector<Tet>& tets_;
  std::vector<int>* region_;
  std::vector<bool> alive_;
  std::vector<std::vector<int>> star_;
};

}  // namespace

SliverRepair repair_slivers(std::vector<Point3>& nodes, std::vector<Tet>& tets, double target_deg, std::vector<int>* region) {
  SliverRepair report;
  bool changed_any = false;
  for (int pass = 0; pass < 20; ++pass) {
    std::vector<std::pair<double, int>> bad;
    double worst = tets.empty() ? 0 : 180;
    for (int t = 0; t < static_cast<int>(tets.size()); ++t) {
      const double q = min_dihedral_deg(nodes, tets[t]);
      worst = std::min(worst, q);
      if (q < target_deg) bad.push_back({q, t});
    }
    if (pass == 0) report.min_dihedral_before_deg = report.min_dihedral_after_deg = worst;
    if (bad.empty()) break;
    RepairMesh mesh(nodes, tets, region);
    std::sort(bad.begin(), bad.end());
    bool changed = false;
    for (const auto& [q, t] : bad) {
      if (!mesh.alive(t) || mesh.quality(t) >= target_deg) continue;
      // Flips first (they keep the boundary), then moving a node, then peeling (which cuts a
      // little off the tissue).
      // The 4-4 flips, edge removals and interface caps only where regions are given (the conforming
      // mesher's repair): the other paths' meshes stay as they were.
      if (mesh.flip32(t, &report.flips32) || (region && mesh.flip44(t, &report.flips44)) ||
          (region && mesh.remove_edge(t, &report.edge_removals)) || mesh.flip23(t, &report.flips23) ||
          (region && mesh.move_cap(t, &report))) {
        changed = true;
      } else if (mesh.relocate(t)) {
        ++report.relocated, changed = true;
      } else if (mesh.peel(t, &report.peeled_volume)) {
        ++report.peeled, changed = true;
      }
    }
    mesh.compact();
    changed_any = changed_any || changed;
    if (!changed) break;
  }
  if (changed_any) report.min_dihedral_after_deg = mesh_quality(nodes, tets).min_dihedral_deg;
  return report;
}

}  // namespace fetouch::meshes
