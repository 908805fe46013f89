// What the hand in the loop met, per probe, for a session's summary: the passivity layer's counters
// and the energy audit (haptics/passivity.h, haptic_loop.h), and the on-line identification's
// comparison with the condensed stiffness (haptics/identification.h); docs/stability.md 9-11.
#pragma once

#include "app/json_writer.h"
#include "app/session.h"
#include "config/scene.h"

namespace fetouch::app {

// The "passivity" and "identification" objects of summary.json (docs/replay.md).
void write_hand_json(JsonWriter& json, const config::Scene& scene, const SessionSummary& s);
// The same as lines of the printed summary.
void print_hand_summary(const config::Scene& scene, const SessionSummary& s);

}  // namespace fetouch::app
