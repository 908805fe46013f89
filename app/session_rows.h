// What a session records of the loop's state (app/session.cc): a frame's row of the recording, the
// passivity layer's counters for the summary, and a tick's figures for a window.
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

// A tick's figures for the window (SessionMonitor): each device's point, proxy, force and layers'
// state, then the tick count. No allocation: the haptic tick calls it.
void publish_tick(SessionMonitor& monitor, long ticks_done, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<haptics::ContactOutput>& out, const DeviceSample* sent, int m) noexcept;

}  // namespace fetouch::app
