// From a volume to a simulation mesh: the one pipeline that `fetouch mesh` and scenes with
// mesh.volume or mesh.phantom both run (imaging/segmentation.h, meshes/volume_mesher.h,
// meshes/labeled_mesher.h). A label map in regions is meshed by the conforming mesher (each region
// a subdomain, interfaces surfaces of their own) when the surface asked is `conforming`; otherwise
// the volume is segmented into one mask, its surface made (`restricted` or `contoured`) and filled,
// and the regions, if any, voted onto the elements afterwards. Every path ends with the same report:
// per region cells, volume against the voxels and quality; per surface its smoothness and its
// distance to the label boundary.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "config/scene.h"
#include "imaging/segmentation.h"
#include "imaging/phantom.h"
#include "meshes/mesh_regions.h"
#include "meshes/volume_mesher.h"

namespace fetouch::app {

struct MeshRequest {
  imaging::TissueSegmentation segmentation;  // unless the regions are meshed as labels
  std::vector<meshes::MeshRegion> regions;   // a label map in regions (empty: one tissue)
  // The regions {imaged: [1], segmented: [2]} made from an intensity image first (image_label_map).
  bool regions_from_image = false;
  config::MeshSurface surface = config::MeshSurface::restricted;
  meshes::MeshingSettings settings;          // settings.restricted_surface follows `surface`
};

struct MeshOutcome {
  meshes::VolumeMesh mesh;
  bool thresholded = false;  // the segmentation thresholded intensities, at:
  float threshold_used = 0;
  std::vector<std::pair<std::string, double>> phases;  // seconds, segmentation and the mesher's own
};

// "8 mm", or with the conforming mesher "8 mm, conforming regions (wall 6 mm, body 3 mm)": what
// `fetouch check` says a scene will be meshed at.
std::string meshing_sizes_text(const config::MeshingOptions& options);

// A scene's meshing options as a request (sizes in mm, the regions' sizes by region).
MeshRequest mesh_request(const config::MeshingOptions& options);

// An intensity image as a label map: 1 where the image shows something (every voxel not 0: the
// reconstruction's cover, its largest piece, closed by the segmentation's `closing` and filled), 2
// where `segmentation` finds the tissue (the bone of a spine, say), 0 elsewhere. So the medium a
// probe presses through is meshed around what the image segments. `threshold_used` as in
// imaging::segment_tissue.
imaging::Volume<float> image_label_map(const imaging::Volume<float>& image, const imaging::TissueSegmentation& segmentation,
                                       float* threshold_used = nullptr);

// Throws std::invalid_argument for contradictory requests (regions with labels or the fetal
// pipeline), std::runtime_error (meshes/ and imaging/'s reasons) when the volume cannot be meshed.
MeshOutcome mesh_volume(const imaging::Volume<float>& volume, MeshRequest request);

}  // namespace fetouch::app
