#include "haptics/phantom.h"

#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>

namespace fetouch::haptics {

namespace hd {

const char* error_name(HDerror code) noexcept {
  switch (code) {
    case kSuccess: return "HD_SUCCESS";
    case 0x100: return "HD_INVALID_ENUM";
    case 0x101: return "HD_INVALID_VALUE";
    case 0x102: return "HD_INVALID_OPERATION";
    case 0x103: return "HD_INVALID_INPUT_TYPE";
    case 0x104: return "HD_BAD_HANDLE";
    case kWarmMotors: return "HD_WARM_MOTORS";
    case kExceededMaxForce: return "HD_EXCEEDED_MAX_FORCE";
    case kExceededMaxForceImpulse: return "HD_EXCEEDED_MAX_FORCE_IMPULSE";
    case kExceededMaxVelocity: return "HD_EXCEEDED_MAX_VELOCITY";
    case kForceError: return "HD_FORCE_ERROR";
    case kDeviceFault: return "HD_DEVICE_FAULT";
    case kDeviceAlreadyInitiated: return "HD_DEVICE_ALREADY_INITIATED";
    case kCommError: return "HD_COMM_ERROR";
    case kCommConfigError: return "HD_COMM_CONFIG_ERROR";
    case kTimerError: return "HD_TIMER_ERROR";
    case kIllegalBegin: return "HD_ILLEGAL_BEGIN";
    case kIllegalEnd: return "HD_ILLEGAL_END";
    case kFrameError: return "HD_FRAME_ERROR";
    case kInvalidPriority: return "HD_INVALID_PRIORITY";
    case kSchedulerFull: return "HD_SCHEDULER_FULL";
    case kInvalidLicense: return "HD_INVALID_LICENSE";
    default: return nullptr;
  }
}

}  // namespace hd

namespace {

constexpr const char* kInstall =
    "install OpenHaptics for Linux and the Touch device driver from 3D Systems, or set FETOUCH_LIBHD "
    "(or the scene's device.library) to its libHD.so";

// "HD_DEVICE_FAULT (0x300): <the driver's text>" into `out` (no allocation: the servo thread uses it).
void describe_error(const hd::Api& api, const hd::HDErrorInfo& e, char* out, std::size_t size) noexcept {
  const char* name = hd::error_name(e.errorCode);
  const char* text = api.hdGetErrorString ? api.hdGetErrorString(e.errorCode) : nullptr;
  std::snprintf(out, size, "%s (0x%x, internal %d): %s", name ? name : "unknown HD error", e.errorCode,
                e.internalErrorCode, text && text[0] ? text : "no text from the driver");
}

std::string error_text(const hd::Api& api, const hd::HDErrorInfo& e) {
  char text[256];
  describe_error(api, e, text, sizeof text);
  return text;
}

}  // namespace

namespace detail {

// The scheduler of one HD library: the vendor's servo thread, shared by every device it drives.
class HdScheduler final : public ServoClock {
 public:
  explicit HdScheduler(const hd::Api& api) : api_(api) {}
  // The servo thread running (state queries need it: hdScheduleSynchronous).
  void ensure_running() {
    if (started_) return;
    while (api_.hdGetError().errorCode != hd::kSuccess) {
    }
    api_.hdStartScheduler();
    const hd::HDErrorInfo e = api_.hdGetError();
    if (e.errorCode != hd::kSuccess) throw std::runtime_error("the PHANTOM's servo loop could not start: " + error_text(api_, e));
    started_ = true;
  }
  void start(Tick tick, void* context) override {
    tick_ = tick, context_ = context;
    running_ = true;
    ensure_running();
    handle_ = api_.hdScheduleAsynchronous(&HdScheduler::callback, this, hd::kMaxSchedulerPriority);
    const hd::HDErrorInfo e = api_.hdGetError();
    if (e.errorCode != hd::kSuccess) {
      running_ = false;
      api_.hdUnschedule(handle_);
      throw std::runtime_error("the PHANTOM's servo loop could not start: " + error_text(api_, e));
    }
  }
  void stop() noexcept override {
    running_ = false;
    if (started_) api_.hdStopScheduler();  // returns once the servo thread has stopped
    api_.hdUnschedule(handle_);
    started_ = false;
  }
  double period_s() const noexcept override { return period_s_; }
  void set_period(double s) { period_s_ = s; }

 private:
  static hd::HDCallbackCode callback(void* self) {
    auto* s = static_cast<HdScheduler*>(self);
    if (!s->running_.load(std::memory_order_relaxed)) return hd::kCallbackDone;
    if (!s->tick_(s->context_)) {
      s->running_ = false;
      return hd::kCallbackDone;
    }
    return hd::kCallbackContinue;
  }
  const hd::Api& api_;
  Tick tick_ = nullptr;
  void* context_ = nullptr;
  std::atomic<bool> running_{false};
  bool started_ = false;
  hd::HDSchedulerHandle handle_ = 0;
  double period_s_ = 1e-3;
};

// A loaded HD library: its entry points and its scheduler.
struct LoadedHd {
  hd::Api api{};
  std::unique_ptr<HdScheduler> scheduler;
};

}  // namespace detail

namespace {

using detail::HdScheduler;
using Loaded = detail::LoadedHd;

std::map<std::string, Loaded>& libraries() {
  static std::map<std::string, Loaded> loaded;
  return loaded;
}

Loaded& loaded(const std::string& path) {
  auto found = libraries().find(path);
  if (found != libraries().end()) return found->second;
  dlerror();
  void* handle = dlopen(path.c_str(), RTLD_LAZY | RTLD_GLOBAL);
  if (!handle) {
    const char* why = dlerror();
    throw std::runtime_error("no PHANTOM driver: " + path + " could not be loaded (" + (why ? why : "no reason given") +
                             "); " + kInstall);
  }
  Loaded l;
  const auto resolve = [&](auto& entry, const char* name) {
    dlerror();
    void* symbol = dlsym(handle, name);
    const char* why = dlerror();
    if (!symbol || why)
      throw std::runtime_error("no PHANTOM driver: " + path + " has no " + name + " (" + (why ? why : "a null symbol") +
                               "); it is not OpenHaptics' libHD.so 3.x: " + kInstall);
    entry = reinterpret_cast<std::remove_reference_t<decltype(entry)>>(symbol);
  };
  hd::Api& a = l.api;
  resolve(a.hdInitDevice, "hdInitDevice");
  resolve(a.hdDisableDevice, "hdDisableDevice");
  resolve(a.hdMakeCurrentDevice, "hdMakeCurrentDevice");
  resolve(a.hdBeginFrame, "hdBeginFrame");
  resolve(a.hdEndFrame, "hdEndFrame");
  resolve(a.hdGetError, "hdGetError");
  resolve(a.hdGetErrorString, "hdGetErrorString");
  resolve(a.hdEnable, "hdEnable");
  resolve(a.hdDisable, "hdDisable");
  resolve(a.hdGetDoublev, "hdGetDoublev");
  resolve(a.hdGetIntegerv, "hdGetIntegerv");
  resolve(a.hdGetString, "hdGetString");
  resolve(a.hdSetDoublev, "hdSetDoublev");
  resolve(a.hdCheckCalibration, "hdCheckCalibration");
  resolve(a.hdStartScheduler, "hdStartScheduler");
  resolve(a.hdStopScheduler, "hdStopScheduler");
  resolve(a.hdScheduleAsynchronous, "hdScheduleAsynchronous");
  resolve(a.hdScheduleSynchronous, "hdScheduleSynchronous");
  resolve(a.hdUnschedule, "hdUnschedule");
  Loaded& kept = libraries()[path];
  kept.api = l.api;
  kept.scheduler = std::make_unique<HdScheduler>(kept.api);
  return kept;
}

std::string shown_name(const std::string& name) { return name.empty() ? "the default PHANTOM" : "the PHANTOM '" + name + "'"; }

// Opens `name` and reads what it says of itself; the handle in `handle`.
PhantomInfo open_device(const hd::Api& api, const std::string& name, hd::HHD& handle) {
  while (api.hdGetError().errorCode != hd::kSuccess) {
  }
  handle = api.hdInitDevice(name.empty() ? nullptr : name.c_str());
  const hd::HDErrorInfo e = api.hdGetError();
  if (e.errorCode != hd::kSuccess || handle == hd::kInvalidHandle)
    throw std::runtime_error("could not open " + shown_name(name) + ": " + error_text(api, e) +
                             "; check that it is plugged in and switched on, that its name is the one in the "
                             "vendor's set-up tool (Touch_Setup), and that you may open its device file "
                             "(/dev/ttyACM* or /dev/fw*: add yourself to the dialout group)");
  api.hdMakeCurrentDevice(handle);
  PhantomInfo info;
  info.name = name;
  const char* model = api.hdGetString(hd::kDeviceModelType);
  const char* serial = api.hdGetString(hd::kDeviceSerialNumber);
  info.model = model ? model : "unknown";
  info.serial = serial ? serial : "unknown";
  api.hdGetDoublev(hd::kUsableWorkspaceDimensions, info.workspace_mm);
  api.hdGetDoublev(hd::kNominalMaxForce, &info.max_force_n);
  api.hdGetDoublev(hd::kNominalMaxContinuousForce, &info.max_continuous_force_n);
  api.hdGetDoublev(hd::kNominalMaxStiffness, &info.max_stiffness_n_per_mm);
  hd::HDint rate = 0;
  api.hdGetIntegerv(hd::kUpdateRate, &rate);
  info.update_rate_hz = rate;
  const hd::HDenum calibration = api.hdCheckCalibration();
  info.calibrated = calibration == hd::kCalibrationOk;
  info.calibration = calibration == hd::kCalibrationOk            ? "ok"
                     : calibration == hd::kCalibrationNeedsUpdate ? "needs an update"
                                                                 : "needs manual input";
  return info;
}

}  // namespace

std::string hd_library_path(const std::string& configured) {
  if (!configured.empty()) return configured;
  const char* from_environment = std::getenv("FETOUCH_LIBHD");
  return from_environment && from_environment[0] ? from_environment : "libHD.so";
}

const hd::Api& load_hd_library(const std::string& path) { return loaded(path).api; }

PhantomInfo describe_phantom(const std::string& library, const std::string& name) {
  const hd::Api& api = load_hd_library(hd_library_path(library));
  hd::HHD handle = hd::kInvalidHandle;
  PhantomInfo info = open_device(api, name, handle);
  api.hdDisableDevice(handle);
  return info;
}

PhantomDevice::PhantomDevice(const PhantomSettings& settings)
    : library_(loaded(hd_library_path(settings.library))), api_(library_.api), workspace_(settings.mapping, settings.period_s),
      clamp_n_(settings.max_force_n), off_length_(std::max<long>(1, std::lround(0.1 / settings.period_s))) {
  info_ = open_device(api_, settings.name, handle_);
  const auto refuse = [&](const std::string& why) {
    api_.hdDisableDevice(handle_);
    throw std::runtime_error(shown_name(settings.name) + " (" + info_.model + ", serial " + info_.serial + ") " + why);
  };
  if (!info_.calibrated)
    refuse("is not calibrated (its calibration " + info_.calibration +
           "): put the stylus in its inkwell (Touch, Omni) or hold the arm in its reset position (Desktop, Premium) "
           "and run the vendor's Touch_Diagnostic calibration, then start again");
  if (info_.update_rate_hz > 0 && std::abs(info_.update_rate_hz * settings.period_s - 1) > 0.05)
    refuse("servos at " + std::to_string(static_cast<int>(info_.update_rate_hz)) + " Hz, but the scene's haptic rate is " +
           std::to_string(static_cast<int>(std::lround(1 / settings.period_s))) + " Hz; set haptics.rate_hz to the device's rate");
  if (info_.max_continuous_force_n > 0 && std::isfinite(info_.max_continuous_force_n))
    clamp_n_ = std::min(clamp_n_, info_.max_continuous_force_n);
  for (hd::HDenum capability : {hd::kForceOutput, hd::kMaxForceClamping, hd::kSoftwareForceLimit, hd::kForceRamping})
    api_.hdEnable(capability);
  const hd::HDErrorInfo e = api_.hdGetError();
  if (e.errorCode != hd::kSuccess) refuse("refused force output: " + error_text(api_, e));
  library_.scheduler->set_period(settings.period_s);
}

PhantomDevice::~PhantomDevice() {
  api_.hdMakeCurrentDevice(handle_);
  api_.hdDisable(hd::kForceOutput);
  api_.hdDisableDevice(handle_);
}

Eigen::Vector3d PhantomDevice::position_now() {
  library_.scheduler->ensure_running();
  struct Query {
    PhantomDevice* self;
    double position[3];
  } query{this, {0, 0, 0}};
  api_.hdScheduleSynchronous(
      [](void* q) -> hd::HDCallbackCode {
        auto* x = static_cast<Query*>(q);
        const hd::Api& api = x->self->api_;
        api.hdMakeCurrentDevice(x->self->handle_);
        api.hdBeginFrame(x->self->handle_);
        api.hdGetDoublev(hd::kCurrentPosition, x->position);
        api.hdEndFrame(x->self->handle_);
        return hd::kCallbackDone;
      },
      &query, hd::kDefaultSchedulerPriority);
  const hd::HDErrorInfo e = api_.hdGetError();
  if (e.errorCode != hd::kSuccess) throw std::runtime_error("could not read " + shown_name(info_.name) + "'s position: " + error_text(api_, e));
  DeviceState device;
  device.position_m = 1e-3 * Eigen::Vector3d(query.position[0], query.position[1], query.position[2]);
  if (!device.position_m.allFinite()) device.position_m.setZero();
  Workspace mapping = workspace_;  // a copy: the query must not press the clutch
  return mapping.to_scene(device).position_m;
}

ServoClock* PhantomDevice::servo_clock() noexcept { return library_.scheduler.get(); }

DeviceState PhantomDevice::read() noexcept {
  api_.hdMakeCurrentDevice(handle_);
  api_.hdBeginFrame(handle_);
  double position[3] = {0, 0, 0}, velocity[3] = {0, 0, 0};
  hd::HDint buttons = 0;
  api_.hdGetDoublev(hd::kCurrentPosition, position);
  api_.hdGetDoublev(hd::kCurrentVelocity, velocity);
  api_.hdGetIntegerv(hd::kCurrentButtons, &buttons);
  DeviceState device;
  for (int i = 0; i < 3; ++i) device.position_m[i] = 1e-3 * position[i], device.velocity_m_per_s[i] = 1e-3 * velocity[i];
  device.buttons = static_cast<std::uint32_t>(buttons);
  if (!device.position_m.allFinite()) device.position_m.setZero();
  if (!device.velocity_m_per_s.allFinite()) device.velocity_m_per_s.setZero();
  return workspace_.to_scene(device);
}

Eigen::Vector3d PhantomDevice::write(const Eigen::Vector3d& force_n) noexcept {
  Eigen::Vector3d sent;
  Eigen::Vector3d force = workspace_.to_device(force_n, sent);
  const double norm = force.norm();
  if (!std::isfinite(norm)) force.setZero(), sent.setZero();
  if (norm > clamp_n_) force *= clamp_n_ / norm, sent *= clamp_n_ / norm;
  if (off_ticks_ > 0 || fault_[0]) {
    force.setZero(), sent.setZero();
    if (off_ticks_ > 0 && --off_ticks_ == 0) workspace_.restart_ramp();
  }
  const double out[3] = {force[0], force[1], force[2]};
  api_.hdMakeCurrentDevice(handle_);
  api_.hdSetDoublev(hd::kCurrentForce, out);
  api_.hdEndFrame(handle_);
  for (int popped = 0; popped < 64; ++popped) {
    const hd::HDErrorInfo e = api_.hdGetError();
    if (e.errorCode == hd::kSuccess) break;
    if (hd::is_force_error(e.errorCode)) {
      ++recoverable_;
      off_ticks_ = off_length_;  // off until 100 ms pass without one
    } else if (!fault_[0]) {
      describe_error(api_, e, fault_, sizeof fault_);
    }
  }
  return sent;
}

}  // namespace fetouch::haptics
