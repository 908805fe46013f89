// Smooth surfaces to draw for a mesh whose regions were voted onto its elements (the default
// scene's `surface: contoured`): there every interface between regions is a staircase of element
// faces, which the trainer would draw as spikes. Here each region's boundary is contoured from the
// label map the mesh was made from (its indicator smoothed by a Gaussian, cut at one half, smoothed
// without shrinking and decimated towards `triangle_mm`), and each of its points is embedded in the
// tetrahedron of the mesh that holds it, so that the solver's displacement moves it (P1: exact
// interpolation; SOFA's visual mappings do the same). The mechanics are the mesh's; only what is
// drawn is smooth.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/trainer/trainer_session.h"
#include "config/scene.h"
#include "imaging/phantom.h"

namespace fetouch::app::trainer {

// What one region draws of its boundary: the triangles it shares with a larger region (the region
// around it; as TissueView draws mesh faces), oriented out of it, with the material across each.
// Points in metres, each carried by a tetrahedron of the mesh.
struct LabelSurface {
  unsigned int material = 0;
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<unsigned int, 3>> triangles;
  std::vector<unsigned int> across;
  std::vector<unsigned int> tetrahedron;          // per point: the mesh's tetrahedron (MeshView index)
  std::vector<std::array<float, 4>> weights;      // per point: its barycentric weights there
};

struct LabelSurfaceSettings {
  double smoothing_mm = 1.0;  // the indicator's Gaussian (standard deviation)
  // The drawn triangles: as many as max_triangles per region, and no smaller than triangle_mm (so a
  // small region, the more curved, has the smaller triangles).
  double triangle_mm = 1.0;
  double max_triangles = 3000;
};

// The surfaces of `mesh`'s regions from `labels` (region name -> labels, as the scene's
// meshing.regions), for the regions MeshView names. Regions that own no interface draw nothing.
std::vector<LabelSurface> label_surfaces(const imaging::Volume<std::uint8_t>& labels,
                                         const std::vector<std::pair<std::string, std::vector<int>>>& regions,
                                         const MeshView& mesh, const LabelSurfaceSettings& settings = {});

// The label map a scene's voted regions were meshed from: the phantom's labels, or a label-map
// volume's; none for a scene without regions, a conforming mesh (its interfaces are surfaces
// already), or regions made from an intensity image. Throws std::runtime_error naming the volume
// that cannot be read.
std::optional<imaging::Volume<std::uint8_t>> scene_label_map(const config::Scene& scene);

// The surfaces a scene's mesh draws (label_surfaces of scene_label_map; none where it has no label
// map), kept in `cache` and made again only when the mesh changes (another scene, an exercise's new
// fetus: keyed by the scene's file and the mesh's sizes and coordinates). `made_s`: the seconds it
// took when made now, else -1. Throws as scene_label_map.
struct LabelSurfaceCache {
  std::string key;
  std::vector<LabelSurface> surfaces;
};
const std::vector<LabelSurface>& scene_label_surfaces(const config::Scene& scene, const MeshView& mesh,
                                                      LabelSurfaceCache& cache, double& made_s);

// Per point, the tetrahedron of `mesh` that holds it (or, outside the mesh, the one nearest by
// its barycentric coordinates) and the barycentric weights there, whose affine map it follows.
void embed_points(const MeshView& mesh, const std::vector<std::array<double, 3>>& points,
                  std::vector<unsigned int>& tetrahedron, std::vector<std::array<float, 4>>& weights);

}  // namespace fetouch::app::trainer
