#include "app/trainer/ultrasound_volume.h"

#include <algorithm>
#include <cstdint>

#include "app/scene_mesh.h"
#include "imaging/phantom.h"
#include "imaging/volume_io.h"

namespace fetouch::app::trainer {

namespace {

template <class T>
ReferenceVolume in_metres(const imaging::Volume<T>& v) {
  ReferenceVolume r;
  r.dimensions = v.dimensions;
  for (int d = 0; d < 3; ++d) r.spacing_m[d] = 1e-3 * v.spacing_mm[d], r.origin_m[d] = 1e-3 * v.origin_mm[d];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) r.direction(a, b) = v.direction[3 * a + b];
  r.data.assign(v.data.begin(), v.data.end());
  return r;
}

}  // namespace

ReferenceVolume scene_ultrasound(const config::Scene& scene, double& gain, std::string& description) {
  gain = 1;
  ReferenceVolume volume;
  if (scene.mesh.source == config::MeshSource::phantom) {
    const imaging::PhantomSettings p = phantom_settings(scene.mesh.phantom);
    volume = in_metres(imaging::make_phantom(p).image);
    description = "the phantom's B-mode image (seed " + std::to_string(p.seed) + ")";
  } else if (scene.mesh.source == config::MeshSource::volume) {
    try {
      volume = in_metres(imaging::read_volume(scene.mesh.path));
    } catch (const std::exception& e) {
      throw std::runtime_error(scene.mesh.path.string() + ": " + e.what());
    }
    description = scene.mesh.path.filename().string();
  } else {
    description = "the mesh's cross-section (the scene has no ultrasound volume)";
    return volume;
  }
  // The gain: the 99.5th percentile of a sample of the voxels to white.
  std::vector<float> sample;
  const std::size_t step = std::max<std::size_t>(1, volume.data.size() / 200000);
  for (std::size_t i = 0; i < volume.data.size(); i += step) sample.push_back(volume.data[i]);
  if (!sample.empty()) {
    const std::size_t k = static_cast<std::size_t>(0.995 * double(sample.size() - 1));
    std::nth_element(sample.begin(), sample.begin() + static_cast<long>(k), sample.end());
    if (sample[k] > 0) gain = 255.0 / sample[k];
  }
  return volume;
}

}  // namespace fetouch::app::trainer
