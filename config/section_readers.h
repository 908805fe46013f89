// The readers of a scene's sections that live in files of their own (boundary_reader.cc,
// effects_reader.cc, material_reader.cc, session_reader.cc), and the helpers they share with
// scene_loader.cc. Internal to config/.
#pragma once

#include <string>
#include <vector>

#include "config/scene.h"
#include "config/yaml_reader.h"

namespace fetouch::config::detail {

// The name a choice table gives a value ("?" if none).
template <class E>
const char* name_of(const Choices<E>& choices, E value) {
  for (const auto& c : choices)
    if (c.second == value) return c.first.c_str();
  return "?";
}

std::string format_number(double value);
// Reports each key of `keys` present in `map` as not used in the situation `why` describes.
void reject_keys(MapView& map, const std::vector<std::string>& keys, const std::string& why);

// The choices of the effects section (effects_reader.cc).
extern const Choices<Effect> kEffects;
extern const Choices<TimeIntegrator> kIntegrators;
extern const Choices<PressureVolumeLaw> kLaws;
void read_effects(MapView& scene, Effects& out);  // effects_reader.cc

// `material` and `materials` (material_reader.cc): at least one of them.
void read_materials(MapView& scene, Scene& out);
void read_boundary(MapView& scene, std::vector<BoundaryRegion>& out);  // boundary_reader.cc
void read_solver(MapView& scene, Solver& out);                        // session_reader.cc
void read_haptics(MapView& scene, Haptics& out);
void read_probes(MapView& scene, std::vector<Probe>& out);
// Rules across sections: rates, probes against the mesh's regions, ...
void check_cross_fields(MapView& scene, Scene& s);

}  // namespace fetouch::config::detail
