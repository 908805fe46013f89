// A scene whose tissue is an ultrasound volume (mesh.volume) or the synthetic phantom
// (mesh.phantom, generated in memory) is meshed here, by the same pipeline
// as `fetouch mesh` (imaging/segmentation.h, meshes/volume_mesher.h), before the solver reads it.
// The mesh is kept in a cache keyed by the volume (path, size, time) and the meshing options, so a
// scene is meshed once: $FETOUCH_CACHE_DIR, else $XDG_CACHE_HOME/fetouch, else ~/.cache/fetouch,
// else the temporary folder. Under MPI rank 0 meshes and the others read its file (Gmsh's result
// varies slightly from run to run, so ranks must not mesh on their own).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "config/scene.h"
#include "imaging/phantom.h"
#include "imaging/segmentation.h"
#include "meshes/volume_mesher.h"

namespace fetouch::app {

// Loads a scene for a command that runs it; a scene with errors has each printed to stderr
// (file:line:column) and gives nothing.
std::optional<config::Scene> load_scene_or_report(const std::string& file);

// The spec unchanged unless it is a volume or the phantom; then a `file` spec of the cached .vtu (meshed now if
// not cached). Throws std::runtime_error naming the volume and what failed.
config::MeshSpec mesh_scene_volume(const config::MeshSpec& spec);
// The same for the scene's own mesh, its refinement ball resolved first (resolved_mesh_spec).
config::MeshSpec mesh_scene_volume(const config::Scene& scene);

// The scene's mesh spec with `meshing.refine: {around_probes: true}` made a ball: the smallest one
// around the bounding box of every replayed or operated probe's trajectory, widened by the largest
// such probe's radius (the elements under a probe are where its force is felt). Unchanged
// otherwise. Throws std::runtime_error naming the scene and the trajectory that cannot be read, or
// saying that no probe has a trajectory.
config::MeshSpec resolved_mesh_spec(const config::Scene& scene);

// The phantom a scene's mesh.phantom describes (seed, spacing, fetus offset and pose; speckle on):
// the mesher takes its labels, the trainer's ultrasound its image.
imaging::PhantomSettings phantom_settings(const config::PhantomSource& source);
// The fetus's head and back directions for a pose (config/fetal_pose.h); none for none (the seed's
// fetus).
std::optional<imaging::PhantomSettings::Orientation> phantom_orientation(const std::optional<config::FetalPose>& pose);

std::filesystem::path mesh_cache_dir();
// Where the mesh of a volume or phantom spec is cached (whether it is there yet or not).
std::filesystem::path cached_mesh_path(const config::MeshSpec& spec);

// A segmentation as the mesher takes it: the same voxels, spacing, origin and direction.
meshes::MaskVolume mask_volume(const imaging::Mask& mask);
// A label map's values as labels 0..255 (rounded, clamped), on the volume's grid.
meshes::MaskVolume label_map(const imaging::Volume<float>& volume);

}  // namespace fetouch::app
