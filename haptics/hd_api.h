// The OpenHaptics HD API as Fetouch uses it: its C types, the constant values of HD/hdDefines.h
// (version 3.0; ../shared/reference/openhaptics-hd-api.md), and the entry points resolved from
// libHD.so at run time. Fetouch never includes the vendor's headers nor links the library: the
// values here are the ABI. Units at this boundary are the device's: mm, mm/s, N, N/mm.
#pragma once

#include <cstdint>

namespace fetouch::haptics::hd {

using HHD = unsigned int;
using HDenum = unsigned int;
using HDerror = unsigned int;
using HDuint = unsigned int;
using HDCallbackCode = unsigned int;
using HDint = int;
using HDdouble = double;
using HDushort = unsigned short;
using HDulong = unsigned long;
using HDSchedulerHandle = unsigned long;
using HDboolean = unsigned char;
using HDstring = const char*;
using HDSchedulerCallback = HDCallbackCode (*)(void*);

struct HDErrorInfo {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};

constexpr HHD kInvalidHandle = 0xFFFFFFFF;
constexpr HDCallbackCode kCallbackDone = 0, kCallbackContinue = 1;
constexpr HDushort kMaxSchedulerPriority = 65535, kDefaultSchedulerPriority = 32767;

// Errors.
constexpr HDerror kSuccess = 0;
constexpr HDerror kWarmMotors = 0x200, kExceededMaxForce = 0x201, kExceededMaxForceImpulse = 0x202,
                  kExceededMaxVelocity = 0x203, kForceError = 0x204;
constexpr HDerror kDeviceFault = 0x300, kDeviceAlreadyInitiated = 0x301, kCommError = 0x302,
                  kCommConfigError = 0x303, kTimerError = 0x304;
constexpr HDerror kIllegalBegin = 0x400, kIllegalEnd = 0x401, kFrameError = 0x402;
constexpr HDerror kInvalidPriority = 0x500, kSchedulerFull = 0x501, kInvalidLicense = 0x600;
// The force errors are recoverable: output stops until they clear (iMSTK, OpenHaptics' examples).
constexpr bool is_force_error(HDerror e) { return e >= kWarmMotors && e <= kForceError; }

// State.
constexpr HDenum kCurrentButtons = 0x2000, kCurrentPosition = 0x2050, kCurrentVelocity = 0x2051;
constexpr HDenum kDeviceModelType = 0x2501, kDeviceSerialNumber = 0x2504, kUsableWorkspaceDimensions = 0x2551;
constexpr HDenum kUpdateRate = 0x2600, kNominalMaxStiffness = 0x2602, kNominalMaxForce = 0x2603,
                 kNominalMaxContinuousForce = 0x2604, kForceRampingRate = 0x2608;
constexpr HDenum kCurrentForce = 0x2700;
// Capabilities.
constexpr HDenum kForceOutput = 0x4000, kMaxForceClamping = 0x4001, kForceRamping = 0x4002,
                 kSoftwareForceLimit = 0x4003;
// Calibration.
constexpr HDenum kCalibrationOk = 0x5000, kCalibrationNeedsUpdate = 0x5001, kCalibrationNeedsManualInput = 0x5002;
constexpr HDenum kCalibrationEncoderReset = 1, kCalibrationAuto = 2, kCalibrationInkwell = 4;

// The HD error's name ("HD_DEVICE_FAULT"), or nullptr for a code not listed above.
const char* error_name(HDerror code) noexcept;

// The entry points Fetouch resolves, exactly these (a missing one is named in the error).
struct Api {
  HHD (*hdInitDevice)(HDstring);
  void (*hdDisableDevice)(HHD);
  void (*hdMakeCurrentDevice)(HHD);
  void (*hdBeginFrame)(HHD);
  void (*hdEndFrame)(HHD);
  HDErrorInfo (*hdGetError)();
  HDstring (*hdGetErrorString)(HDerror);
  void (*hdEnable)(HDenum);
  void (*hdDisable)(HDenum);
  void (*hdGetDoublev)(HDenum, HDdouble*);
  void (*hdGetIntegerv)(HDenum, HDint*);
  HDstring (*hdGetString)(HDenum);
  void (*hdSetDoublev)(HDenum, const HDdouble*);
  HDenum (*hdCheckCalibration)();
  void (*hdStartScheduler)();
  void (*hdStopScheduler)();
  HDSchedulerHandle (*hdScheduleAsynchronous)(HDSchedulerCallback, void*, HDushort);
  void (*hdScheduleSynchronous)(HDSchedulerCallback, void*, HDushort);
  void (*hdUnschedule)(HDSchedulerHandle);
};

}  // namespace fetouch::haptics::hd
