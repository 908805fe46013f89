// The exit codes of every fetouch command.
#pragma once

namespace fetouch::app {
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;   // the work itself failed (a solve diverged, a write failed)
constexpr int kExitBadInput = 2;  // bad usage, or input that was rejected (scene, mesh, volume)
}  // namespace fetouch::app
