// The `effects` section of a scene: which effects are simulated and their parameters.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <string>
#include <vector>

#include "config/plausible.h"
#include "config/section_readers.h"
#include "config/yaml_reader.h"

namespace fetouch::config::detail {

const Choices<Effect> kEffects{{"elasticity", Effect::elasticity},
                               {"gravity", Effect::gravity},
                               {"inertia", Effect::inertia},
                               {"damping", Effect::damping},
                               {"incompressibility", Effect::incompressibility},
                               {"cavity", Effect::cavity},
                               {"contact", Effect::contact}};
const Choices<TimeIntegrator> kIntegrators{{"backward_euler", TimeIntegrator::backward_euler},
                                           {"newmark", TimeIntegrator::newmark},
                                           {"hht", TimeIntegrator::hht}};
const Choices<PressureVolumeLaw> kLaws{{"linear", PressureVolumeLaw::linear},
                                       {"isothermal_gas", PressureVolumeLaw::isothermal_gas}};

namespace {

void read_effect_parameters(Reader& reader, Effect effect, const Entry& e, Effects& out) {
  switch (effect) {
    case Effect::gravity: {
      MapView map(reader, e.value, e.path, e.key_mark, {"acceleration_m_per_s2"});
      if (map.valid()) map.vec3("acceleration_m_per_s2", out.gravity_m_per_s2);
      break;
    }
    case Effect::inertia: {
      MapView map(reader, e.value, e.path, e.key_mark, {"integrator", "hht_alpha"});
      if (!map.valid()) break;
      map.choice("integrator", out.integrator, kIntegrators);
      if (map.has("hht_alpha") && out.integrator != TimeIntegrator::hht)
        reject_keys(map, {"hht_alpha"}, "unless integrator is hht");
      else
        map.number("hht_alpha", out.hht_alpha, {-1.0 / 3.0, 0, false, false});
      break;
    }
    case Effect::damping: {
      MapView map(reader, e.value, e.path, e.key_mark,
                  {"mass_coefficient_per_s", "stiffness_coefficient_s"});
      if (!map.valid()) break;
      map.number("mass_coefficient_per_s", out.rayleigh_mass_per_s, {0, 1e4, false, false, "up to 10^4 per second"});
      map.number("stiffness_coefficient_s", out.rayleigh_stiffness_s, {0, 1, false, false, "up to 1 s"});
      break;
    }
    case Effect::cavity: {
      MapView map(reader, e.value, e.path, e.key_mark,
                  {"surface", "regions", "law", "initial_pressure_pa", "bulk_modulus_pa"});
      if (!map.valid()) break;
      if (map.has("surface") == map.has("regions")) {
        reader.error(e.key_mark, e.path,
                     map.has("surface") ? "give the cavity's surface or its regions, not both"
                                        : "a cavity needs its surface (a boundary physical group) or its regions "
                                          "(the volume regions it holds, such as [fluid, fetus])");
      } else if (map.has("surface")) {
        if (map.text("surface", out.cavity_surface, Need::required) && out.cavity_surface.empty())
          reader.error(map.entry("surface").value_mark, map.child_path("surface"),
                       "expected the name of the mesh's physical group that bounds the cavity");
      } else {
        out.cavity_regions = detail::read_name_list(reader, map.entry("regions"), "volume regions such as [fluid, fetus]");
      }
      map.choice("law", out.cavity_law, kLaws);
      map.number("initial_pressure_pa", out.cavity_initial_pressure_pa, plausible::pressure_pa);
      map.number("bulk_modulus_pa", out.cavity_bulk_modulus_pa, plausible::bulk_modulus_pa);
      break;
    }
    default:
      reader.error(e.value_mark, e.path,
                   std::string("effect '") + name_of(kEffects, effect) + "' takes no parameters");
  }
}

}  // namespace

void read_effects(MapView& scene, Effects& out) {
  const Entry e = scene.entry("effects");
  Reader& reader = scene.reader();
  if (e.value.IsNull()) return;  // "effects:" with nothing: elasticity only
  if (!e.value.IsSequence()) {
    reader.error(e.value_mark, e.path,
                 "expected a list of effects (- gravity, - contact, ...), got " +
                     detail::describe_node(e.value));
    return;
  }
  std::vector<std::string> names;
  for (const auto& c : kEffects) names.push_back(c.first);
  std::set<Effect> seen;
  for (size_t i = 0; i < e.value.size(); ++i) {
    const YAML::Node item = e.value[i];
    const std::string item_path = e.path + "[" + std::to_string(i) + "]";
    Entry name_entry;  // the effect's name, written alone or as the single key of a mapping
    Entry parameters;
    name_entry.path = item_path;
    name_entry.value_mark = name_entry.key_mark = item.Mark();
    if (item.IsScalar()) {
      name_entry.value.reset(item);
    } else if (item.IsMap() && item.size() == 1) {
      name_entry.value.reset(item.begin()->first);
      name_entry.value_mark = item.begin()->first.Mark();
      parameters.present = true;
      parameters.key_mark = name_entry.value_mark;
      parameters.value.reset(item.begin()->second);
      parameters.value_mark = item.begin()->second.IsNull() ? name_entry.value_mark
                                                            : item.begin()->second.Mark();
    } else {
      reader.error(item.Mark(), item_path,
                   "expected an effect name, or one name with its parameters (- gravity: "
                   "{acceleration_m_per_s2: [0, 0, -9.81]}), got " + detail::describe_node(item));
      continue;
    }
    auto word = detail::read_text(reader, name_entry);
    if (!word) continue;
    auto found = std::find(names.begin(), names.end(), *word);
    if (found == names.end()) {
      std::string message = "unknown effect '" + *word + "'; effects are elasticity, gravity, "
                            "inertia, damping, incompressibility, cavity and contact";
      const std::string suggestion = closest_match(*word, names);
      if (!suggestion.empty()) message += "; did you mean '" + suggestion + "'?";
      reader.error(name_entry.value_mark, item_path, message);
      continue;
    }
    const Effect effect = kEffects[found - names.begin()].second;
    const std::string effect_path = e.path + "." + *word;
    if (!seen.insert(effect).second) {
      reader.error(name_entry.value_mark, effect_path, "effect '" + *word + "' is listed twice");
      continue;
    }
    out.listed.push_back(effect);
    if (parameters.present && !parameters.value.IsNull()) {
      parameters.path = effect_path;
      read_effect_parameters(reader, effect, parameters, out);
    } else if (effect == Effect::cavity) {
      reader.error(name_entry.value_mark, effect_path,
                   "a cavity needs its surface or its regions: - cavity: {surface: <physical group>} or "
                   "- cavity: {regions: [fluid, fetus]}");
    }
  }
}


}  // namespace fetouch::config::detail
