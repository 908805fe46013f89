// A stand-in for OpenHaptics' libHD.so, built by the tests only (not installed, not shipped): the same
// C entry points with the real constant values (../shared/reference/openhaptics-hd-api.md), and a
// simulated device behind them, so that Fetouch's PHANTOM family runs through the very code path it
// takes with the vendor's library (dlopen, dlsym, the scheduler's servo thread).
//
// The simulated device: a servo thread at 1 kHz (absolute deadlines) calling the scheduled callbacks;
// per device a hand: a mass pulled by a spring and a damper along a trajectory and pushed by the force
// it is sent, integrated exactly over each tick for inputs held over it (zero-order hold), as
// haptics::VirtualOperator does. It records every force it is sent, checks each is finite and within
// its nominal maximum continuous force, and injects faults on request. Set by the environment:
//   FETOUCH_STANDIN_DEVICES      device names, comma-separated (default "Default PHANToM"; the
//                                default device, hdInitDevice(NULL), is the first)
//   FETOUCH_STANDIN_TRAJECTORY   the hand's target: CSV t, x, y, z (s, m, device frame); NAME=FILE
//                                pairs, comma-separated, for several devices; none: at rest at 0
//   FETOUCH_STANDIN_HAND         mass_kg,stiffness_n_per_m,damping_n_s_per_m (default 0.3,300,8)
//   FETOUCH_STANDIN_BUTTONS      BUTTON@FROM-TO;... : button held from FROM to TO seconds
//   FETOUCH_STANDIN_MAX_FORCE    nominal max continuous force, N (default 3.3; max force 2x)
//   FETOUCH_STANDIN_LOG          a CSV written when the device is disabled: one row per force sent
//   FETOUCH_STANDIN_FAULT        init | uncalibrated | force_burst | device_fault | stall
//   FETOUCH_STANDIN_FAULT_AT     when a force burst, device fault or stall starts (s of session time)
// Session time, the hand's motion and the button schedule start with the first asynchronous callback
// scheduled (the session's servo tick); until then the hand rests at its trajectory's start.
#include "standin_hd_device.h"

using namespace standin;

extern "C" {

HHD hdInitDevice(HDstring name) {
  State& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  s.fault = env("FETOUCH_STANDIN_FAULT");  // read again: a test process may open several times
  s.fault_at = std::stod(env("FETOUCH_STANDIN_FAULT_AT", "1.0"));
  if (s.fault == "init") {
    push_error(kCommError, kInvalidHandle, -1);
    return kInvalidHandle;
  }
  for (HHD h = 0; h < s.devices.size(); ++h)
    if (!name || s.devices[h].name == name) {
      s.devices[h].open = true;
      s.current = h;
      return h;
    }
  push_error(kCommConfigError, kInvalidHandle);
  return kInvalidHandle;
}

void hdDisableDevice(HHD h) {
  State& s = state();
  {
    std::lock_guard<std::mutex> lock(s.mutex);
    if (!device(h)) return push_error(kBadHandle, h);
    s.devices[h].open = false;
  }
  write_log();
}

void hdMakeCurrentDevice(HHD h) {
  std::lock_guard<std::mutex> lock(state().mutex);
  if (!device(h)) return push_error(kBadHandle, h);
  state().current = h;
}

HHD hdGetCurrentDevice() { return state().current; }

void hdBeginFrame(HHD h) {
  std::lock_guard<std::mutex> lock(state().mutex);
  Device* d = device(h);
  if (!d) return push_error(kBadHandle, h);
  if (d->in_frame) return push_error(kIllegalBegin, h);
  d->in_frame = true;
  for (double& f : d->pending) f = 0;  // a frame that sets no force sends none
}

#ifndef STANDIN_WITHOUT_END_FRAME  // the broken variant: a library without one of the entry points
void hdEndFrame(HHD h) {
  State& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  Device* d = device(h);
  if (!d) return push_error(kBadHandle, h);
  if (!d->in_frame) return push_error(kIllegalEnd, h);
  d->in_frame = false;
  const double t = servo_time();
  const double norm = std::sqrt(d->pending[0] * d->pending[0] + d->pending[1] * d->pending[1] + d->pending[2] * d->pending[2]);
  if (!std::isfinite(norm) || norm > s.max_force * (1 + 1e-9)) ++d->violations;
  Logged l{t, {d->pending[0], d->pending[1], d->pending[2]}, {1e3 * d->x[0], 1e3 * d->x[1], 1e3 * d->x[2]}};
  d->log.push_back(l);
  for (int c = 0; c < 3; ++c) d->force[c] = d->pending[c];
  if (s.fault == "force_burst" && t >= s.fault_at && t < s.fault_at + 0.05) push_error(kExceededMaxForce, h);
  if (s.fault == "device_fault" && t >= s.fault_at) push_error(kDeviceFault, h, 7);
}
#endif

HDErrorInfo hdGetError() {
  std::lock_guard<std::mutex> lock(state().mutex);
  auto& errors = state().errors;
  if (errors.empty()) return {kSuccess, 0, state().current};
  const HDErrorInfo e = errors.back();
  errors.pop_back();
  return e;
}

HDstring hdGetErrorString(HDerror code) {
  switch (code) {
    case kSuccess: return "no error";
    case kExceededMaxForce: return "Exceeded max force";
    case kDeviceFault: return "Device fault (stand-in: injected)";
    case kCommError: return "Communication error (stand-in: injected at initialisation)";
    case kCommConfigError: return "Communication configuration error: no device of that name";
    case kBadHandle: return "Invalid handle";
    case kIllegalBegin: return "Illegal begin of frame";
    case kIllegalEnd: return "Illegal end of frame";
    default: return "stand-in: an error";
  }
}

void hdEnable(HDenum) {}
void hdDisable(HDenum) {}
HDboolean hdIsEnabled(HDenum) { return 1; }

void hdGetDoublev(HDenum what, HDdouble* out) {
  State& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  Device* d = device(s.current);
  switch (what) {
    case kCurrentPosition:
      if (d) for (int c = 0; c < 3; ++c) out[c] = 1e3 * d->x[c];
      return;
    case kCurrentVelocity:
      if (d) for (int c = 0; c < 3; ++c) out[c] = 1e3 * d->v[c];
      return;
    case kCurrentTransform:
      for (int i = 0; i < 16; ++i) out[i] = i % 5 == 0 ? 1 : 0;
      if (d) for (int c = 0; c < 3; ++c) out[12 + c] = 1e3 * d->x[c];
      return;
    case kUsableWorkspaceDimensions: {
      const double w[6] = {-80, -60, -35, 80, 60, 35};
      std::memcpy(out, w, sizeof w);
      return;
    }
    case kNominalMaxStiffness: *out = 1.26; return;
    case kNominalMaxForce: *out = 2 * s.max_force; return;
    case kNominalMaxContinuousForce: *out = s.max_force; return;
    case kCurrentForce:
      if (d) for (int c = 0; c < 3; ++c) out[c] = d->pending[c];
      return;
    default: push_error(kInvalidEnum, s.current);
  }
}

void hdGetIntegerv(HDenum what, HDint* out) {
  State& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (what == kUpdateRate) {
    *out = 1000;
  } else if (what == kCurrentButtons) {
    *out = 0;
    const double t = servo_time();
    for (const Button& b : s.buttons)
      if (t >= b.from && t < b.to) *out |= 1 << b.bit;
  } else {
    push_error(kInvalidEnum, s.current);
  }
}

void hdGetBooleanv(HDenum, HDboolean* out) { *out = 0; }
void hdGetFloatv(HDenum what, float* out) {
  double d[16];
  hdGetDoublev(what, d);
  *out = static_cast<float>(d[0]);
}
void hdGetLongv(HDenum what, long* out) {
  HDint i = 0;
  hdGetIntegerv(what, &i);
  *out = i;
}

HDstring hdGetString(HDenum what) {
  if (what == kDeviceModelType) return "Fetouch stand-in (simulated PHANTOM)";
  if (what == kDeviceSerialNumber) return "STANDIN-0001";
  return nullptr;
}

void hdSetDoublev(HDenum what, const HDdouble* in) {
  State& s = state();
  std::lock_guard<std::mutex> lock(s.mutex);
  Device* d = device(s.current);
  if (what != kCurrentForce) return push_error(kInvalidEnum, s.current);
  if (!d || !d->in_frame) return push_error(kInvalidOperation, s.current);
  for (int c = 0; c < 3; ++c) d->pending[c] = in[c];
}

HDenum hdCheckCalibration() { return state().fault == "uncalibrated" ? kCalibrationNeedsManualInput : kCalibrationOk; }
void hdUpdateCalibration(HDenum) {}

void hdStartScheduler() {
  State& s = state();
  if (s.running.exchange(true)) return;
  s.servo = std::thread(servo_loop);
}

void hdStopScheduler() {
  State& s = state();
  if (!s.running.exchange(false)) return;
  if (s.servo.joinable()) s.servo.join();
}

void hdSetSchedulerRate(HDulong) {}

HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback callback, void* data, HDushort) {
  std::lock_guard<std::mutex> lock(state().mutex);
  state().callbacks.emplace_back(callback, data);
  state().session_started = true;
  return state().callbacks.size();
}

// Runs on the servo thread, the caller waiting (as the vendor's does); without a running scheduler
// the vendor's library would block for ever: here it is an error.
void hdScheduleSynchronous(HDSchedulerCallback callback, void* data, HDushort) {
  State& s = state();
  if (!s.running.load()) {
    std::lock_guard<std::mutex> lock(s.mutex);
    return push_error(kInvalidOperation, s.current);
  }
  std::atomic<bool> done{false};
  struct Once {
    HDSchedulerCallback callback;
    void* data;
    std::atomic<bool>* done;
  } once{callback, data, &done};
  {
    std::lock_guard<std::mutex> lock(s.mutex);
    s.callbacks.emplace_back(
        [](void* o) -> HDCallbackCode {
          auto* x = static_cast<Once*>(o);
          x->callback(x->data);
          x->done->store(true);
          return 0;
        },
        &once);
  }
  while (!done.load()) std::this_thread::sleep_for(std::chrono::microseconds(200));
}

void hdUnschedule(HDSchedulerHandle) {
  std::lock_guard<std::mutex> lock(state().mutex);
  state().callbacks.clear();
}

HDboolean hdWaitForCompletion(HDSchedulerHandle, HDuint) { return 1; }
HDdouble hdGetSchedulerTimeStamp() { return 0; }

}  // extern "C"
