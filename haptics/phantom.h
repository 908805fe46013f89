// The PHANTOM family (3D Systems Touch and Touch X, PHANTOM Omni, Desktop and Premium) through the
// OpenHaptics HD API, loaded at run time: Fetouch builds and runs without the SDK, and says why when
// a scene asks for a device that cannot be had (docs/devices.md).
//
// The library: the scene's device.library, else $FETOUCH_LIBHD, else "libHD.so" on the loader's
// path. It is loaded once (dlopen, RTLD_LAZY | RTLD_GLOBAL, as CHAI3D does) and never unloaded (the
// vendor driver misbehaves when loaded twice); exactly the entry points of hd::Api are resolved.
//
// The device, once opened: its error stack emptied; HD_FORCE_OUTPUT, HD_MAX_FORCE_CLAMPING,
// HD_SOFTWARE_FORCE_LIMIT and HD_FORCE_RAMPING enabled; its calibration checked (an uncalibrated
// device is refused, saying how to calibrate it); its force clamped to its nominal maximum
// continuous force (the scene's max_force_n if that is lower). Each servo tick, in the vendor's
// scheduler thread: hdBeginFrame, pose and buttons read (mm and mm/s become m and m/s here, and
// only here), the session's tick, the force set, hdEndFrame, the error stack read. Force errors
// (0x200 to 0x204) are recoverable: the force is off until 100 ms pass without one, then ramps in
// again, and they are counted; any other error is the device's fault and ends the session.
#pragma once

#include <memory>
#include <string>

#include "haptics/device.h"
#include "haptics/hd_api.h"
#include "haptics/workspace.h"

namespace fetouch::haptics {

// The path to load: `configured` if not empty, else $FETOUCH_LIBHD if set, else "libHD.so".
std::string hd_library_path(const std::string& configured);

// The loaded HD library (one per path and process, never unloaded). Throws std::runtime_error with
// one line: the library or the entry point that is missing, the dlerror text, and what to install.
const hd::Api& load_hd_library(const std::string& path);

namespace detail {
struct LoadedHd;  // a loaded library and its scheduler (phantom.cc)
}

struct PhantomInfo {
  std::string name;  // as asked for ("" is the default device)
  std::string model, serial;
  double workspace_mm[6] = {0, 0, 0, 0, 0, 0};  // usable workspace: min x, y, z, max x, y, z
  double max_force_n = 0, max_continuous_force_n = 0, max_stiffness_n_per_mm = 0;
  double update_rate_hz = 0;
  bool calibrated = false;
  std::string calibration;  // "ok", "needs an update", "needs manual input"
};

struct PhantomSettings {
  std::string name;     // the device's name in the vendor's set-up tool; "" the default device
  std::string library;  // see hd_library_path
  double max_force_n = 3.3;
  double period_s = 1e-3;
  WorkspaceMapping mapping;
};

class PhantomDevice final : public Device {
 public:
  // Opens the device as described above. Throws std::runtime_error naming the device, the HD error
  // (name, code and the driver's text) and what to do.
  explicit PhantomDevice(const PhantomSettings& settings);
  ~PhantomDevice() override;  // force off, the device disabled
  PhantomDevice(const PhantomDevice&) = delete;
  PhantomDevice& operator=(const PhantomDevice&) = delete;

  DeviceState read() noexcept override;
  Eigen::Vector3d write(const Eigen::Vector3d& force_n) noexcept override;
  bool finished() const noexcept override { return false; }
  long ticks() const noexcept override { return -1; }
  ServoClock* servo_clock() noexcept override;
  const char* fault() const noexcept override { return fault_[0] ? fault_ : nullptr; }
  long recoverable_errors() const noexcept override { return recoverable_; }

  // Where the device is now, in the scene (a query on the servo thread: not in the tick). Throws
  // std::runtime_error with the HD error.
  Eigen::Vector3d position_now();

  const PhantomInfo& info() const { return info_; }
  double force_clamp_n() const { return clamp_n_; }
  const Workspace& workspace() const { return workspace_; }

 private:
  detail::LoadedHd& library_;
  const hd::Api& api_;  // library_'s entry points
  hd::HHD handle_ = hd::kInvalidHandle;
  PhantomInfo info_;
  Workspace workspace_;
  double clamp_n_;
  long off_ticks_ = 0, off_length_;
  long recoverable_ = 0;
  char fault_[256] = {};
};

// Opens the device `name` long enough to describe it (no force is sent). Throws as PhantomDevice.
PhantomInfo describe_phantom(const std::string& library, const std::string& name);

}  // namespace fetouch::haptics
