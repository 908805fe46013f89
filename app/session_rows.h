// What a session records of the loop's state (app/session.cc): a frame's row of the recording, and
// the passivity layer's counters for the summary.
#pragma once

#include <vector>

#include "app/recording.h"
#include "app/session.h"
#include "haptics/haptic_loop.h"

namespace fetouch::app {

// The frame's row of the recording from the update the tick now holds, taken up at time_s.
FrameRecord frame_record(const haptics::FrameSlot& slot, double time_s);
// Adds the energy audit of frame `frame`'s ticks (HapticLoop::frame_energy()) to a row.
void add_energy_audit(FrameRecord& record, long frame, const std::vector<haptics::FrameEnergy>& energy);

// The passivity layer's counters per contact at the end of a session.
std::vector<PassivitySummary> passivity_summary(const haptics::HapticLoop& loop);
// The identification's comparison with the condensed stiffness, per device.
std::vector<IdentificationSummary> identification_summary(const haptics::HapticLoop& loop);

}  // namespace fetouch::app
