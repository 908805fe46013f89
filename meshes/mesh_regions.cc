#include "meshes/mesh_regions.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <stdexcept>

namespace fetouch::meshes {

MeshRegion parse_region(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("region '" + text + "': " + why + " (expected NAME=LABEL[,LABEL...], e.g. fetus=3,4,5,6)");
  };
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos) throw bad("no '='");
  MeshRegion region;
  region.name = text.substr(0, equals);
  if (region.name.empty()) throw bad("no name");
  for (const char c : region.name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') throw bad("a name of letters, digits, '_' and '-' only");
  std::string rest = text.substr(equals + 1);
  std::size_t start = 0;
  while (start <= rest.size()) {
    const std::size_t comma = std::min(rest.find(',', start), rest.size());
    const std::string word = rest.substr(start, comma - start);
    std::size_t used = 0;
    int label = -1;
    try {
      label = std::stoi(word, &used);
    } catch (const std::exception&) {
    }
    if (word.empty() || used != word.size() || label < 1 || label > 255) throw bad("label '" + word + "' is not a whole number in 1..255");
    region.labels.push_back(label);
    start = comma + 1;
  }
  return region;
}

namespace {

// The label map's voxel containing a point (mm), or -1 outside the grid.
struct LabelLookup {
  const MaskVolume& v;
  long index(const std::array<double, 3>& x_mm, std::array<int, 3>* ijk = nullptr) const {
    std::array<int, 3> at{};
    for (int c = 0; c < 3; ++c) {
      double t = 0;  // (D' (x - origin))_c / spacing_c
      for (int r = 0; r < 3; ++r) t += v.direction[3 * r + c] * (x_mm[r] - v.origin_mm[r]);
      at[c] = static_cast<int>(std::lround(t / v.spacing_mm[c]));
      if (at[c] < 0 || at[c] >= v.dimensions[c]) return -1;
    }
    if (ijk) *ijk = at;
    return (long(at[2]) * v.dimensions[1] + at[1]) * v.dimensions[0] + at[0];
  }
};

}  // namespace

void assign_regions(VolumeMesh& mesh, const MaskVolume& labels, const std::vector<MeshRegion>& regions) {
  std::array<int, 256> region_of_label;
  region_of_label.fill(-1);
  for (std::size_t r = 0; r < regions.size(); ++r)
    for (const int label : regions[r].labels) {
      if (region_of_label[label] >= 0)
        throw std::invalid_argument("label " + std::to_string(label) + " is in regions " +
                                    regions[std::size_t(region_of_label[label])].name + " and " + regions[r].name);
      region_of_label[label] = static_cast<int>(r);
    }
  const LabelLookup lookup{labels};
  const auto region_at = [&](const std::array<double, 3>& x_mm) {
    const long i = lookup.index(x_mm);
    return i < 0 ? -1 : region_of_label[labels.data[std::size_t(i)]];
  };
  // The nearest voxel of any region to a point, within 10 voxels (-1: none).
  const auto nearest_region = [&](const std::array<double, 3>& x_mm) {
    std::array<int, 3> c{};
    if (lookup.index(x_mm, &c) < 0) return -1;
    int best = -1;
    long best_d2 = 1L << 40;
    for (int radius = 1; radius <= 10 && best < 0; ++radius)
      for (int k = c[2] - radius; k <= c[2] + radius; ++k)
        for (int j = c[1] - radius; j <= c[1] + radius; ++j)
          for (int i = c[0] - radius; i <= c[0] + radius; ++i) {
            if (i < 0 || j < 0 || k < 0 || i >= labels.dimensions[0] || j >= labels.dimensions[1] || k >= labels.dimensions[2])
              continue;
            const int r = region_of_label[labels.data[(std::size_t(k) * labels.dimensions[1] + j) * labels.dimensions[0] + i]];
            const long d2 = long(i - c[0]) * (i - c[0]) + long(j - c[1]) * (j - c[1]) + long(k - c[2]) * (k - c[2]);
            if (r >= 0 && d2 < best_d2) best = r, best_d2 = d2;
          }
    return best;
  };

  mesh.region_names.clear();
  for (const auto& r : regions) mesh.region_names.push_back(r.name);
  // Sample points spread evenly through a tetrahedron: barycentric (a + 1/2) / (n + 2) for the
  // whole numbers a_0 + a_1 + a_2 + a_3 = n, all strictly inside (35 points for n = 4, about one per
  // voxel for elements of 5 to 6 voxels): the counts estimate how much of the element each region's
  // labels cover.
  constexpr int n_split = 4;
  std::vector<std::array<double, 4>> samples;
  for (int a = 0; a <= n_split; ++a)
    for (int b = 0; a + b <= n_split; ++b)
      for (int c = 0; a + b + c <= n_split; ++c) {
        const auto w = [](int k) { return (k + 0.5) / (n_split + 2); };
        samples.push_back({w(a), w(b), w(c), w(n_split - a - b - c)});
      }
  const std::size_t n = regions.size();
  std::vector<std::vector<int>> votes(mesh.tetrahedra.size(), std::vector<int>(n, 0));
  std::vector<double> volume_m3(mesh.tetrahedra.size());
  std::vector<double> covered_m3(n, 0), assigned_m3(n, 0);  // each region's labels inside the mesh; its elements
  mesh.region.assign(mesh.tetrahedra.size(), 0);
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const Tet& tet = mesh.tetrahedra[t];
    const auto& p = mesh.nodes_m;
    volume_m3[t] = tet_signed_volume(p[std::size_t(tet[0])], p[std::size_t(tet[1])], p[std::size_t(tet[2])], p[std::size_t(tet[3])]);
    std::array<std::array<double, 3>, 4> corner_mm{};
    std::array<double, 3> centroid{0, 0, 0};
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 3; ++c) {
        corner_mm[k][c] = 1e3 * p[std::size_t(tet[k])][c];
        centroid[c] += 0.25 * corner_mm[k][c];
      }
    std::vector<int>& count = votes[t];
    for (const auto& w : samples) {
      std::array<double, 3> x{0, 0, 0};
      for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c) x[c] += w[k] * corner_mm[k][c];
      if (const int r = region_at(x); r >= 0) ++count[std::size_t(r)];
    }
    const int most = *std::max_element(count.begin(), count.end());
    int chosen = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
    if (most == 0 || std::count(count.begin(), count.end(), most) > 1) {
      // No sample in any region, or two regions cover as much: the centroid's region, or its nearest.
      const int at_centroid = region_at(centroid);
      const int nearest = at_centroid >= 0 ? at_centroid : nearest_region(centroid);
      if (nearest >= 0 && (most == 0 || count[std::size_t(nearest)] == most)) chosen = nearest;
    }
    mesh.region[t] = chosen;
    assigned_m3[std::size_t(chosen)] += volume_m3[t];
    for (std::size_t r = 0; r < n; ++r) covered_m3[r] += volume_m3[t] * count[r] / double(samples.size());
  }

  // The most-covered region loses volume on a curved interface (a convex region by 2 to 4 % at 5 to
  // 6 voxels per element, its neighbour gains it). The elements that two regions share nearly
  // evenly (the other covering at least 40 % as much as the chosen one) are then handed over, most
  // evenly shared first, whenever that brings both regions' element volumes closer (relatively) to
  // the volume their labels cover inside the mesh. Every hand-over stays within an element of the
  // labels' interface; the result does not depend on the order Gmsh numbers the elements.
  struct HandOver {
    double share;  // the other region's cover over the chosen one's
    std::size_t t;
    int to;
  };
  std::vector<HandOver> candidates;
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const int own = votes[t][std::size_t(mesh.region[t])];
    for (std::size_t r = 0; r < n; ++r)
      if (int(r) != mesh.region[t] && own > 0 && votes[t][r] >= 0.4 * own)
        candidates.push_back({double(votes[t][r]) / own, t, int(r)});
  }
  std::sort(candidates.begin(), candidates.end(), [&](const HandOver& a, const HandOver& b) {
    if (a.share != b.share) return a.share > b.share;
    return volume_m3[a.t] > volume_m3[b.t];
  });
  const auto misfit = [&](std::size_t r, double assigned) {
    return covered_m3[r] > 0 ? std::pow(assigned / covered_m3[r] - 1, 2) : 0.0;
  };
  std::vector<char> handed(mesh.tetrahedra.size(), 0);
  for (const HandOver& c : candidates) {
    if (handed[c.t]) continue;
    const std::size_t from = std::size_t(mesh.region[c.t]), to = std::size_t(c.to);
    const double v = volume_m3[c.t];
    const double before = misfit(from, assigned_m3[from]) + misfit(to, assigned_m3[to]);
    const double after = misfit(from, assigned_m3[from] - v) + misfit(to, assigned_m3[to] + v);
    if (after >= before) continue;
    assigned_m3[from] -= v, assigned_m3[to] += v;
    mesh.region[c.t] = c.to;
    handed[c.t] = 1;
  }

  report_regions(mesh, labels, regions);
}

void report_regions(VolumeMesh& mesh, const MaskVolume& labels, const std::vector<MeshRegion>& regions) {
  const std::size_t n = regions.size();
  std::array<int, 256> region_of_label;
  region_of_label.fill(-1);
  for (std::size_t r = 0; r < n; ++r)
    for (const int label : regions[r].labels) region_of_label[std::size_t(label)] = static_cast<int>(r);
  mesh.region_names.clear();
  for (const auto& r : regions) mesh.region_names.push_back(r.name);
  // The report: elements, volume against the voxels', quality; outer and interface faces.
  mesh.regions.assign(n, {});
  const double voxel_m3 = labels.spacing_mm[0] * labels.spacing_mm[1] * labels.spacing_mm[2] * 1e-9;
  for (std::size_t r = 0; r < n; ++r) mesh.regions[r].name = regions[r].name, mesh.regions[r].min_dihedral_deg = 180;
  for (const std::uint8_t label : labels.data)
    if (region_of_label[label] >= 0) mesh.regions[std::size_t(region_of_label[label])].voxel_volume_m3 += voxel_m3;
  std::map<std::array<int, 3>, int> face_owner;
  std::map<std::array<int, 3>, std::array<int, 3>> oriented;  // a face as its first element has it
  mesh.interface_triangles = 0;
  mesh.interfaces.clear();
  mesh.interface_regions.clear();
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t) {
    const Tet& tet = mesh.tetrahedra[t];
    VolumeMesh::RegionReport& report = mesh.regions[std::size_t(mesh.region[t])];
    ++report.tetrahedra;
    const auto& p = mesh.nodes_m;
    report.volume_m3 += tet_signed_volume(p[std::size_t(tet[0])], p[std::size_t(tet[1])], p[std::size_t(tet[2])], p[std::size_t(tet[3])]);
    report.min_dihedral_deg = std::min(report.min_dihedral_deg, min_dihedral_deg(p, tet));
    for (int f = 0; f < 4; ++f) {
      // Face f, opposite corner f, turned so that its normal points out of the (positive) tetrahedron.
      std::array<int, 3> out{tet[(f + 1) % 4], tet[(f + 2) % 4], tet[(f + 3) % 4]};
      if (f % 2 == 1) std::swap(out[1], out[2]);
      std::array<int, 3> face = out;
      std::sort(face.begin(), face.end());
      const auto [it, inserted] = face_owner.emplace(face, static_cast<int>(t));
      if (inserted) {
        oriented[face] = out;
        continue;
      }
      const int first = mesh.region[std::size_t(it->second)], second = mesh.region[t];
      if (first != second) {
        ++mesh.interface_triangles;
        // Out of the lower region: the first element's orientation if it is the lower one.
        mesh.interfaces.push_back(first < second ? oriented[face] : out);
        mesh.interface_regions.push_back({std::min(first, second), std::max(first, second)});
      }
      oriented.erase(face);
      face_owner.erase(it);
    }
  }
  mesh.boundary_region.assign(mesh.boundary.size(), 0);
  for (std::size_t b = 0; b < mesh.boundary.size(); ++b) {
    std::array<int, 3> face = mesh.boundary[b];
    std::sort(face.begin(), face.end());
    const auto it = face_owner.find(face);
    if (it == face_owner.end()) throw std::logic_error("a boundary triangle is no element's face");
    mesh.boundary_region[b] = mesh.region[std::size_t(it->second)];
    ++mesh.regions[std::size_t(mesh.boundary_region[b])].outer_triangles;
  }
  for (const auto& report : mesh.regions)
    if (report.tetrahedra == 0)
      throw std::runtime_error("region " + report.name + " got no element at this element size (" +
                               std::to_string(report.voxel_volume_m3 * 1e6) + " cm^3 of voxels): mesh finer or merge it");
}

std::vector<std::pair<std::string, long>> interface_groups(const VolumeMesh& mesh) {
  std::map<std::array<int, 2>, long> counts;
  for (const auto& pair : mesh.interface_regions) ++counts[pair];
  std::vector<std::pair<std::string, long>> groups;
  for (const auto& [pair, faces] : counts)
    groups.emplace_back(mesh.region_names.at(std::size_t(pair[0])) + "_" + mesh.region_names.at(std::size_t(pair[1])), faces);
  return groups;
}

}  // namespace fetouch::meshes
