// What a session takes from a scene: the 1 kHz loop's settings and one device per probe.
#pragma once

#include <memory>

#include "config/scene.h"
#include "haptics/devices.h"
#include "haptics/haptic_loop.h"
#include "haptics/workspace.h"

namespace fetouch::app {

haptics::HapticLoopSettings loop_settings(const config::Scene& scene);

// The device's workspace mapping and buttons as the scene gives them.
haptics::WorkspaceMapping workspace_mapping(const config::Device& device);

// The operator's hand and its scripted events (docs/devices.md), as the device takes them.
haptics::HandParameters hand_parameters(const config::HandModel& hand);
std::vector<haptics::HandEvent> hand_events(const config::HandModel& hand);

// The probe's device: a replay or a virtual operator along `path` (required for those), or a
// PHANTOM opened with the scene's mapping and clamp. Throws std::runtime_error in one line naming
// the probe and why (for a PHANTOM: the library, the entry point or the device error, and what to do).
std::unique_ptr<haptics::Device> make_device(const config::Probe& probe, const config::Scene& scene,
                                             const haptics::HapticLoopSettings& settings, const haptics::Trajectory* path);

}  // namespace fetouch::app
