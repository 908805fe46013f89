// CGAL's restricted Delaunay surface of a mask (meshes/restricted_surface.h). The only translation
// unit that includes CGAL: its templates are heavy.
#include "meshes/restricted_surface.h"

#include "imaging/separable_filter.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_3/initialize_triangulation_from_gray_image.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace fetouch::meshes {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
// Sequential: CGAL's parallel refinement (TBB) halves the time on two cores but gives another mesh
// every run, and a scene's figures (its hard cases, its frame times) hang on its mesh.
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;

constexpr int kPad = 4;  // empty voxels around the mask, so that its level closes at the faces

constexpr const char* kTooThin =
    "meshing: no part of the segmentation is thick enough to have a surface once its voxels' steps are smoothed (a "
    "single voxel, a line or a diagonal chain of voxels)";

// The mask (0/1) padded and blurred by a Gaussian of `sigma` voxels (imaging's separable filter).
std::vector<float> blurred_mask(const MaskVolume& mask, double sigma, std::array<int, 3>& n) {
  for (int d = 0; d < 3; ++d) n[d] = mask.dimensions[d] + 2 * kPad;
  std::vector<float> field(static_cast<std::size_t>(n[0]) * n[1] * n[2], 0.f);
  for (int k = 0; k < mask.dimensions[2]; ++k)
    for (int j = 0; j < mask.dimensions[1]; ++j)
      for (int i = 0; i < mask.dimensions[0]; ++i)
        if (mask.data[(std::size_t(k) * mask.dimensions[1] + j) * mask.dimensions[0] + i])
          field[(std::size_t(k + kPad) * n[1] + (j + kPad)) * n[0] + (i + kPad)] = 1.f;
  const std::vector<double> kernel = imaging::gaussian_kernel(sigma);
  for (int axis = 0; axis < 3; ++axis) imaging::convolve_axis(field, n, axis, kernel, imaging::Faces::renormalised);
  return field;
}

// CGAL bounds the triangles' circumradii, and Delaunay refinement leaves most of them well under the
// bound: with a regular triangle's (edge / sqrt 3) the phantom's uterus at 5.8 mm had edges of
// 4.45 mm on average and twice the elements Gmsh makes at that size; 1.3 times that gives edges of
// 5.81 mm.
constexpr double kCircumradiusPerEdge = 1.3 / 1.7320508075688772;

// The triangles' size, finer in the balls (the refinement of MeshingSettings; the finest where they
// overlap), in the padded grid's frame.
struct FacetSize {
  struct Ball {
    Point3 centre{};
    double radius = 0;
  };
  double size = 0, inner = 0;
  std::vector<Ball> balls;
  double operator()(const Kernel::Point_3& p, int, const Domain::Index&) const {
    double edge = size;
    for (const Ball& b : balls) {
      const double r = std::sqrt((p.x() - b.centre[0]) * (p.x() - b.centre[0]) + (p.y() - b.centre[1]) * (p.y() - b.centre[1]) +
                                 (p.z() - b.centre[2]) * (p.z() - b.centre[2]));
      edge = std::min(edge, r <= b.radius       ? inner
                            : r >= 2 * b.radius ? size
                                                : inner + (size - inner) * (r - b.radius) / b.radius);
    }
    return kCircumradiusPerEdge * edge;
  }
};

}  // namespace

RestrictedSurface restricted_surface(const MaskVolume& mask, const MeshingSettings& s, double distance_mm) {
  namespace params = CGAL::parameters;
  const auto started = std::chrono::steady_clock::now();
  if (std::none_of(mask.data.begin(), mask.data.end(), [](std::uint8_t v) { return v != 0; }))
    throw std::runtime_error("meshing: the segmentation is empty (no voxel set)");
  std::array<int, 3> n{};
  // Half a voxel: a line or sheet one voxel thick stays above the level (its centre keeps 0.62 of
  // its value; 0.32 at 0.7 voxel, which cut a white-matter segmentation into pieces and lost 3 % of
  // it), while the voxels' steps are smoothed away.
  const std::vector<float> field = blurred_mask(mask, 0.5, n);
  // Nothing at the level (a single voxel keeps 0.49 of its value): CGAL would search for a surface
  // without end.
  if (std::none_of(field.begin(), field.end(), [](float v) { return v >= 0.5f; }))
    throw std::runtime_error(kTooThin);
  _image* raw = ::_createImage(std::size_t(n[0]), std::size_t(n[1]), std::size_t(n[2]), 1, mask.spacing_mm[0],
                               mask.spacing_mm[1], mask.spacing_mm[2], sizeof(float), WK_FLOAT, SGN_SIGNED);
  std::memcpy(raw->data, field.data(), field.size() * sizeof(float));
  const CGAL::Image_3 image(raw);
  // The same mesh every run: CGAL's default generator (seeding the pieces' first points) starts
  // from the clock.
  CGAL::get_default_random() = CGAL::Random(1);
  CGAL::Random random(1);
  const Domain domain = Domain::create_gray_image_mesh_domain(image, params::iso_value = 0.5f, params::value_outside = 0.f,
                                                               params::relative_error_bound = 1e-4, params::p_rng = &random);
  FacetSize size{s.element_size_mm, s.refine_size_mm, {}};
  const auto& d = mask.direction;
  for (const MeshingSettings::RefineBall& ball : s.refine_balls)
    if (ball.radius_mm > 0) size.balls.push_back({padded_grid_point(mask, ball.center_mm, kPad), ball.radius_mm});
  const Criteria criteria(params::facet_angle = 25, params::facet_size = size, params::facet_distance = distance_mm);
  Complex complex;
  RestrictedSurface out;
  {
    // Seeds on every connected piece (CGAL's default shoots random rays and can miss a small one);
    // CGAL tells of them on the standard output, where a report in JSON goes: kept.
    std::ostringstream told;
    std::streambuf* const was = std::cout.rdbuf(told.rdbuf());
    try {
      initialize_triangulation_from_gray_image(complex, domain, image, criteria, 0.5f, float());
    } catch (...) {
      std::cout.rdbuf(was);
      throw;
    }
    std::cout.rdbuf(was);
    std::istringstream lines(told.str());
    for (std::string line; std::getline(lines, line);)
      if (line.find("components were found") != std::string::npos) out.pieces = std::atoi(line.c_str());
  }
  CGAL::refine_mesh_3(complex, domain, criteria, params::no_perturb(), params::no_exude(), params::manifold());

  const Triangulation& tr = complex.triangulation();
  std::unordered_map<Triangulation::Vertex_handle, int> index;
  std::vector<Point3> grid;  // in the padded grid's frame
  const auto node = [&](Triangulation::Vertex_handle v) {
    auto [it, added] = index.try_emplace(v, static_cast<int>(grid.size()));
    if (added) {
      const auto p = tr.point(v).point();
      grid.push_back({p.x(), p.y(), p.z()});
    }
    return it->second;
  };
  for (auto facet = complex.facets_in_complex_begin(); facet != complex.facets_in_complex_end(); ++facet) {
    auto [cell, i] = *facet;
    if (!complex.is_in_complex(cell)) std::tie(cell, i) = tr.mirror_facet(*facet);  // seen from inside
    Triangle t{node(cell->vertex((i + 1) & 3)), node(cell->vertex((i + 2) & 3)), node(cell->vertex((i + 3) & 3))};
    const auto q = tr.point(cell->vertex(i)).point();
    // Facing out: the inner cell's fourth vertex behind the triangle.
    if (tet_signed_volume(grid[std::size_t(t[0])], grid[std::size_t(t[1])], grid[std::size_t(t[2])], {q.x(), q.y(), q.z()}) > 0)
      std::swap(t[1], t[2]);
    out.triangles.push_back(t);
  }
  if (out.triangles.empty()) throw std::runtime_error(kTooThin);
  // Into space: the index axes along the direction cosines, about the first voxel.
  for (const Point3& g : grid) {
    Point3 q{};
    for (int r = 0; r < 3; ++r) {
      q[r] = mask.origin_mm[r];
      for (int c = 0; c < 3; ++c) q[r] += d[3 * r + c] * (g[c] - kPad * mask.spacing_mm[c]);
    }
    out.nodes_mm.push_back(q);
  }
  const double det = d[0] * (d[4] * d[8] - d[5] * d[7]) - d[1] * (d[3] * d[8] - d[5] * d[6]) + d[2] * (d[3] * d[7] - d[4] * d[6]);
  if (det < 0)  // a mirroring placement turns every triangle inside out
    for (auto& t : out.triangles) std::swap(t[1], t[2]);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace fetouch::meshes
