// The ultrasound volume a scene's tissue comes from, for the trainer's ultrasound view: the
// phantom's B-mode image (with speckle, from the scene's seed and fetus offset: the same label map
// its mesh was made from) or the volume file a scene meshes. Empty for other scenes (the view then
// shows the mesh's cross-section).
#pragma once

#include <string>

#include "app/trainer/deformed_slice.h"
#include "config/scene.h"

namespace fetouch::app::trainer {

// `gain` receives the factor that maps the volume's 99.5th percentile to 255. Throws
// std::runtime_error naming the volume when it cannot be read.
ReferenceVolume scene_ultrasound(const config::Scene& scene, double& gain, std::string& description);

}  // namespace fetouch::app::trainer
