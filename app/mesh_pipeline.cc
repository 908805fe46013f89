#include "app/mesh_pipeline.h"

#include <chrono>
#include <sstream>
#include <stdexcept>

#include "app/scene_mesh.h"
#include "meshes/interface_quality.h"
#include "meshes/labeled_mesher.h"

namespace fetouch::app {

std::string meshing_sizes_text(const config::MeshingOptions& m) {
  const auto mm = [](double metres) {
    std::ostringstream out;
    out << metres * 1e3 << " mm";
    return out.str();
  };
  std::string text = mm(m.target_size_m);
  if (!m.refine_balls.empty()) {
    std::string balls;
    for (const auto& ball : m.refine_balls) {
      const auto& c = ball.center_m;
      balls += (balls.empty() ? "" : ", ") + mm(ball.radius_m) + " of (" + mm(c[0]) + ", " + mm(c[1]) + ", " + mm(c[2]) + ")";
    }
    text += ", " + mm(m.refine_size_m) + " within " + balls;
    if (m.refine_around_probes) text += m.refine_balls.size() > 1 ? " around each probe's path" : " around the probes' paths";
  }
  if (m.surface != config::MeshSurface::conforming) return text;
  text += ", conforming regions";
  if (m.sizes_m.empty()) return text;
  std::string sizes;
  for (const auto& [name, size] : m.sizes_m) sizes += (sizes.empty() ? "" : ", ") + name + " " + mm(size);
  return text + " (" + sizes + "; graded between)";
}

MeshRequest mesh_request(const config::MeshingOptions& m) {
  MeshRequest r;
  auto& seg = r.segmentation;
  if (m.regions.empty()) seg.labels = m.labels;
  seg.fetus = m.fetus, seg.closing = m.closing_voxels;
  seg.smoothing_mm = m.smoothing_sigma_m * 1e3;
  if (m.threshold) seg.threshold = static_cast<float>(*m.threshold);
  seg.smoothing = m.smoothing == config::SmoothingFilter::none     ? imaging::TissueSegmentation::Smoothing::none
                  : m.smoothing == config::SmoothingFilter::median ? imaging::TissueSegmentation::Smoothing::median
                                                                   : imaging::TissueSegmentation::Smoothing::gaussian;
  for (const auto& [name, labels] : m.regions) r.regions.push_back({name, labels});
  r.regions_from_image = m.regions_from_image;
  r.surface = m.surface;
  auto& s = r.settings;
  s.element_size_mm = m.target_size_m * 1e3;
  for (const auto& region : r.regions) {
    double size = 0;
    for (const auto& [name, size_m] : m.sizes_m)
      if (name == region.name) size = size_m * 1e3;
    s.region_size_mm.push_back(size);
  }
  for (const auto& ball : m.refine_balls) {
    meshes::MeshingSettings::RefineBall b;
    for (int d = 0; d < 3; ++d) b.center_mm[std::size_t(d)] = ball.center_m[std::size_t(d)] * 1e3;
    b.radius_mm = ball.radius_m * 1e3;
    s.refine_balls.push_back(b);
  }
  if (!m.refine_balls.empty()) s.refine_size_mm = m.refine_size_m * 1e3;
  return r;
}

imaging::Volume<float> image_label_map(const imaging::Volume<float>& image, const imaging::TissueSegmentation& segmentation,
                                       float* threshold_used) {
  const imaging::Mask inside = imaging::segment_tissue(image, segmentation, threshold_used);
  imaging::TissueSegmentation cover;
  cover.threshold = 0.5f;  // any echo; the reconstruction leaves 0 where no frame passed
  cover.smoothing = imaging::TissueSegmentation::Smoothing::none;
  cover.closing = segmentation.closing;
  const imaging::Mask imaged = imaging::segment_tissue(image, cover);
  imaging::Volume<float> labels;
  labels.dimensions = image.dimensions, labels.spacing_mm = image.spacing_mm, labels.origin_mm = image.origin_mm;
  labels.direction = image.direction;
  labels.data.resize(image.data.size());
  for (std::size_t i = 0; i < labels.data.size(); ++i) labels.data[i] = inside.data[i] ? 2.0f : imaged.data[i] ? 1.0f : 0.0f;
  return labels;
}

MeshOutcome mesh_volume(const imaging::Volume<float>& volume, MeshRequest request) {
  const auto started = std::chrono::steady_clock::now();
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  if (request.regions_from_image) {
    float threshold = 0;
    const imaging::Volume<float> labels = image_label_map(volume, request.segmentation, &threshold);
    const double labelling_s = since(started);
    request.regions_from_image = false;
    request.segmentation = imaging::TissueSegmentation();
    MeshOutcome out = mesh_volume(labels, std::move(request));
    out.phases.insert(out.phases.begin(), {"image regions", labelling_s});
    out.thresholded = true, out.threshold_used = threshold;
    return out;
  }
  MeshOutcome out;
  const bool in_regions = !request.regions.empty();
  if (in_regions && (request.segmentation.fetus || !request.segmentation.labels.empty()))
    throw std::invalid_argument("regions take the labels of a label map themselves; drop labels and the fetal pipeline");
  if (request.surface == config::MeshSurface::conforming && !in_regions)
    throw std::invalid_argument("the conforming mesher meshes a label map in regions: give the regions");
  request.settings.restricted_surface = request.surface == config::MeshSurface::restricted;
  meshes::MaskVolume labels;
  if (in_regions) labels = label_map(volume);
  if (request.surface == config::MeshSurface::conforming) {
    out.mesh = meshes::mesh_labels(labels, request.regions, request.settings);
    out.phases = out.mesh.phases;
    return out;
  }
  auto& seg = request.segmentation;
  if (in_regions)
    for (const auto& r : request.regions) seg.labels.insert(seg.labels.end(), r.labels.begin(), r.labels.end());
  out.thresholded = seg.labels.empty() && !seg.fetus;
  const imaging::Mask mask = imaging::segment_tissue(volume, seg, &out.threshold_used);
  out.phases.push_back({"segmentation", since(started)});
  const meshes::MaskVolume input = mask_volume(mask);
  out.mesh = meshes::mesh_mask(input, request.settings);
  out.phases.insert(out.phases.end(), out.mesh.phases.begin(), out.mesh.phases.end());
  if (in_regions) meshes::assign_regions(out.mesh, labels, request.regions);
  out.mesh.surfaces = meshes::surface_smoothness(out.mesh, in_regions ? labels : input, request.regions);
  return out;
}

}  // namespace fetouch::app
