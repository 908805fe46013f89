#include "app/commands/hand_summary.h"

#include <cstdio>

namespace fetouch::app {

void write_hand_json(JsonWriter& json, const config::Scene& scene, const SessionSummary& s) {
  // The passivity layer per probe (haptics/passivity.h, docs/stability.md).
  json.key("passivity").begin_object();
  json.key("mode").value(config::to_string(scene.haptics.passivity.mode));
  json.key("controller").value(config::to_string(scene.haptics.passivity.controller));
  json.key("probes").begin_array();
  for (const PassivitySummary& p : s.passivity) {
    json.begin_object();
    json.key("generation_events").value(p.generation_events);
    json.key("generating_ticks").value(p.generating_ticks);
    json.key("controller_ticks").value(p.controller_ticks);
    json.key("adjusting_ticks").value(p.adjusting_ticks);
    json.key("max_controller_force_n").value(p.max_controller_force_n);
    json.key("min_port_energy_j").value(p.min_energy_j);
    json.key("min_scale").value(p.min_scale);
    json.key("generating_frames").value(p.generating_frames);
    json.key("max_frame_generation_j").value(p.max_frame_generation_j);
    json.end_object();
  }
  json.end_array();
  json.end_object();
  // On-line identification per probe (haptics/identification.h, docs/stability.md).
  json.key("identification").begin_object();
  json.key("enabled").value(scene.haptics.identification.enabled);
  json.key("bound").value(scene.haptics.identification.bound);
  json.key("probes").begin_array();
  for (const IdentificationSummary& i : s.identification) {
    json.begin_object();
    json.key("frames_compared").value(i.frames_compared);
    json.key("disagreements").value(i.disagreements);
    json.key("first_disagreement_s").value(i.first_disagreement_s);
    json.key("max_relative_difference").value(i.max_relative_difference);
    json.key("last_relative_difference").value(i.last_relative_difference);
    json.end_object();
  }
  json.end_array();
  json.end_object();
}

void print_hand_summary(const config::Scene& scene, const SessionSummary& s) {
  for (std::size_t p = 0; p < s.passivity.size() && p < scene.probes.size(); ++p) {
    const PassivitySummary& ps = s.passivity[p];
    std::printf("  passivity %s (%s), %s: %ld generation events, controller on %ld ticks (%.2f %%, acting on %ld), largest "
                "controller force %.3f N, lowest port energy %.3g mJ, stiffness scaled to %.3f at the least\n",
                config::to_string(scene.haptics.passivity.mode), config::to_string(scene.haptics.passivity.controller),
                scene.probes[p].name.c_str(), ps.generation_events, ps.controller_ticks,
                s.ticks > 0 ? 100.0 * double(ps.controller_ticks) / double(s.ticks) : 0.0, ps.adjusting_ticks,
                ps.max_controller_force_n, 1e3 * ps.min_energy_j, ps.min_scale);
    std::printf("  energy audit %s: %ld of %ld frames generated energy (over 1 uJ), the most %.3g mJ in one frame\n",
                scene.probes[p].name.c_str(), ps.generating_frames, s.frames, 1e3 * ps.max_frame_generation_j);
  }
  for (std::size_t p = 0; p < s.identification.size() && p < scene.probes.size(); ++p) {
    if (!scene.haptics.identification.enabled) break;
    const IdentificationSummary& is = s.identification[p];
    std::printf("  identification %s: felt stiffness compared with the condensed one at %ld frames, %ld differ by over %.0f %%",
                scene.probes[p].name.c_str(), is.frames_compared, is.disagreements, 100 * scene.haptics.identification.bound);
    if (is.disagreements > 0) std::printf(" (the first at %.2f s)", is.first_disagreement_s);
    if (is.frames_compared > 0)
      std::printf("; largest difference %.1f %%, at the last %.1f %%", 100 * is.max_relative_difference,
                  100 * is.last_relative_difference);
    std::printf("\n");
  }
}

}  // namespace fetouch::app
