// The stand-in 3D Systems OpenHaptics HD runtime (libHD.so.3.4 built from fake_openhaptics.cpp):
// the project's own declarations of the facts it needs, shared by the library and its unit test.
// Every vendor value is written from driver/vendors/SOURCES.md section 2, and the comment beside it
// names the section and the original source it cites. No vendor header is used or copied.
#pragma once

#include <climits>

namespace fake_hd {

// ---- C types (SOURCES.md §2.2; [OH] hdDefines.h lines 32-45). On x86-64 Linux every function is
// a plain C function: HDAPIENTRY's stdcall has no effect there and HDCALLBACK is empty (§2.2,
// hdExport.h 35-39). ----
using HDuint = unsigned int;     // §2.2
using HDboolean = unsigned char;  // §2.2
using HDulong = unsigned long;   // §2.2
using HDushort = unsigned short;  // §2.2
using HDint = int;               // §2.2
using HDfloat = float;           // §2.2
using HDdouble = double;         // §2.2
using HDlong = long;             // §2.2
using HDchar = char;             // §2.2
using HDerror = unsigned int;    // §2.2
using HDenum = unsigned int;     // §2.2
using HDstring = const char*;    // §2.2
using HHD = unsigned int;        // §2.2

// §2.2, hdDefines.h 47-52: three 4-byte fields, returned BY VALUE from hdGetError.
struct HDErrorInfo {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};
static_assert(sizeof(HDErrorInfo) == 12, "HDErrorInfo is three 4-byte fields (SOURCES.md §2.2)");

// §2.3, hdScheduler.h 36-52
using HDCallbackCode = unsigned int;                     // §2.3, hdScheduler.h 36
inline constexpr HDCallbackCode HD_CALLBACK_DONE = 0;      // §2.3, hdScheduler.h 37
inline constexpr HDCallbackCode HD_CALLBACK_CONTINUE = 1;  // §2.3, hdScheduler.h 38
using HDSchedulerHandle = unsigned long;                 // §2.3, hdScheduler.h 41
using HDSchedulerCallback = HDCallbackCode (*)(void* pUserData);  // §2.3, hdScheduler.h 44
using HDWaitCode = unsigned int;                         // §2.3, hdScheduler.h 50
inline constexpr HDWaitCode HD_WAIT_CHECK_STATUS = 0;    // §2.3, hdScheduler.h 51
inline constexpr HDWaitCode HD_WAIT_INFINITE = 1;        // §2.3, hdScheduler.h 52

// Priorities (§2.3, hdDefines.h 253-256; DEFAULT = (MAX+MIN)/2 in C integer arithmetic)
inline constexpr HDushort HD_MAX_SCHEDULER_PRIORITY = USHRT_MAX;  // §2.3 (65535)
inline constexpr HDushort HD_MIN_SCHEDULER_PRIORITY = 0;          // §2.3
inline constexpr HDushort HD_DEFAULT_SCHEDULER_PRIORITY =
    (HD_MAX_SCHEDULER_PRIORITY + HD_MIN_SCHEDULER_PRIORITY) / 2;  // §2.3 (32767)
static_assert(HD_DEFAULT_SCHEDULER_PRIORITY == 32767);

// §2.3, hdDefines.h 278: HD_DEFAULT_DEVICE is a NULL `const char*` ("the first device it finds").
inline constexpr HDstring HD_DEFAULT_DEVICE = nullptr;

// ---- Booleans and handles (§2.4; hdDefines.h 55-56, 275) ----
inline constexpr HDboolean HD_TRUE = 1;               // §2.4, hdDefines.h 55
inline constexpr HDboolean HD_FALSE = 0;              // §2.4, hdDefines.h 56
inline constexpr HHD HD_INVALID_HANDLE = 0xFFFFFFFF;  // §2.4, hdDefines.h 275

// ---- Error codes (§2.4; hdDefines.h 72-105; meanings in [OH-REF] Table A-15) ----
inline constexpr HDerror HD_SUCCESS = 0x0000;                     // §2.4
inline constexpr HDerror HD_INVALID_ENUM = 0x0100;                // §2.4 (function errors)
inline constexpr HDerror HD_INVALID_VALUE = 0x0101;               // §2.4
inline constexpr HDerror HD_INVALID_OPERATION = 0x0102;           // §2.4 (not 0x0103 as [PYOH])
inline constexpr HDerror HD_INVALID_INPUT_TYPE = 0x0103;          // §2.4
inline constexpr HDerror HD_BAD_HANDLE = 0x0104;                  // §2.4
inline constexpr HDerror HD_WARM_MOTORS = 0x0200;                 // §2.4 (force errors)
inline constexpr HDerror HD_EXCEEDED_MAX_FORCE = 0x0201;          // §2.4
inline constexpr HDerror HD_EXCEEDED_MAX_FORCE_IMPULSE = 0x0202;  // §2.4
inline constexpr HDerror HD_EXCEEDED_MAX_VELOCITY = 0x0203;       // §2.4
inline constexpr HDerror HD_FORCE_ERROR = 0x0204;                 // §2.4
inline constexpr HDerror HD_DEVICE_FAULT = 0x0300;                // §2.4 (device errors)
inline constexpr HDerror HD_DEVICE_ALREADY_INITIATED = 0x0301;    // §2.4
inline constexpr HDerror HD_COMM_ERROR = 0x0302;                  // §2.4
inline constexpr HDerror HD_COMM_CONFIG_ERROR = 0x0303;           // §2.4
inline constexpr HDerror HD_TIMER_ERROR = 0x0304;                 // §2.4
inline constexpr HDerror HD_ILLEGAL_BEGIN = 0x0400;               // §2.4 (frame errors)
inline constexpr HDerror HD_ILLEGAL_END = 0x0401;                 // §2.4
inline constexpr HDerror HD_FRAME_ERROR = 0x0402;                 // §2.4
inline constexpr HDerror HD_INVALID_PRIORITY = 0x0500;            // §2.4 (scheduler errors)
inline constexpr HDerror HD_SCHEDULER_FULL = 0x0501;              // §2.4
inline constexpr HDerror HD_INVALID_LICENSE = 0x0600;             // §2.4 (licence)

// ---- Get parameters (§2.4; hdDefines.h 115-169; units §2.5, [OH-REF] Appendix A) ----
inline constexpr HDenum HD_CURRENT_BUTTONS = 0x2000;           // §2.4; int mask of HD_DEVICE_BUTTON_*
inline constexpr HDenum HD_CURRENT_SAFETY_SWITCH = 0x2001;     // §2.4 (not modelled)
inline constexpr HDenum HD_CURRENT_INKWELL_SWITCH = 0x2002;    // §2.4 (not modelled)
inline constexpr HDenum HD_CURRENT_POSITION = 0x2050;          // §2.4; 3 doubles, mm (§2.5)
inline constexpr HDenum HD_CURRENT_VELOCITY = 0x2051;          // §2.4; mm/s (§2.5)
inline constexpr HDenum HD_CURRENT_TRANSFORM = 0x2052;         // §2.4; 16, column-major (§2.5)
inline constexpr HDenum HD_CURRENT_ANGULAR_VELOCITY = 0x2053;  // §2.4; rad/s (§2.5)
inline constexpr HDenum HD_CURRENT_JACOBIAN = 0x2054;          // §2.4 (not modelled)
inline constexpr HDenum HD_CURRENT_JOINT_ANGLES = 0x2100;      // §2.4 (not modelled)
inline constexpr HDenum HD_CURRENT_GIMBAL_ANGLES = 0x2150;     // §2.4; rad (§2.5)
inline constexpr HDenum HD_LAST_BUTTONS = 0x2200;              // §2.4
inline constexpr HDenum HD_LAST_POSITION = 0x2250;             // §2.4
inline constexpr HDenum HD_LAST_VELOCITY = 0x2251;             // §2.4
inline constexpr HDenum HD_LAST_TRANSFORM = 0x2252;            // §2.4
inline constexpr HDenum HD_LAST_ANGULAR_VELOCITY = 0x2253;     // §2.4
inline constexpr HDenum HD_LAST_GIMBAL_ANGLES = 0x2350;        // §2.4
inline constexpr HDenum HD_VERSION = 0x2500;                   // §2.4; string (§2.5)
inline constexpr HDenum HD_DEVICE_MODEL_TYPE = 0x2501;         // §2.4; string (§2.5)
inline constexpr HDenum HD_DEVICE_DRIVER_VERSION = 0x2502;     // §2.4; string (§2.5)
inline constexpr HDenum HD_DEVICE_VENDOR = 0x2503;             // §2.4; string (§2.5)
inline constexpr HDenum HD_DEVICE_SERIAL_NUMBER = 0x2504;      // §2.4; string (§2.5)
inline constexpr HDenum HD_DEVICE_FIRMWARE_VERSION = 0x2505;   // §2.4 (not modelled)
inline constexpr HDenum HD_MAX_WORKSPACE_DIMENSIONS = 0x2550;  // §2.4; 6 doubles, mm (§2.5)
inline constexpr HDenum HD_USABLE_WORKSPACE_DIMENSIONS = 0x2551;  // §2.4; 6 doubles, mm (§2.5)
inline constexpr HDenum HD_TABLETOP_OFFSET = 0x2552;           // §2.4 (not modelled)
inline constexpr HDenum HD_INPUT_DOF = 0x2553;                 // §2.4; HDint (§2.5)
inline constexpr HDenum HD_OUTPUT_DOF = 0x2554;                // §2.4; HDint (§2.5)
inline constexpr HDenum HD_CALIBRATION_STYLE = 0x2555;         // §2.4; HDint bitmask (§2.5)
inline constexpr HDenum HD_UPDATE_RATE = 0x2600;               // §2.4; Hz (§2.5)
inline constexpr HDenum HD_INSTANTANEOUS_UPDATE_RATE = 0x2601;  // §2.4; Hz
inline constexpr HDenum HD_NOMINAL_MAX_STIFFNESS = 0x2602;     // §2.4 (not modelled: unit unknown)
inline constexpr HDenum HD_NOMINAL_MAX_FORCE = 0x2603;         // §2.4; N (§2.5)
inline constexpr HDenum HD_NOMINAL_MAX_CONTINUOUS_FORCE = 0x2604;  // §2.4; N (§2.5)
inline constexpr HDenum HD_SOFTWARE_VELOCITY_LIMIT = 0x2606;   // §2.4; also a capability
inline constexpr HDenum HD_SOFTWARE_FORCE_IMPULSE_LIMIT = 0x2607;  // §2.4; also a capability

// ---- Force/torque parameters (§2.4; hdDefines.h 178-212) ----
inline constexpr HDenum HD_CURRENT_FORCE = 0x2700;          // §2.4; 3 doubles, N, device frame
inline constexpr HDenum HD_CURRENT_TORQUE = 0x2701;         // §2.4; deprecated; mN·m (§2.5)
inline constexpr HDenum HD_CURRENT_JOINT_TORQUE = 0x2703;   // §2.4 (not modelled)
inline constexpr HDenum HD_CURRENT_GIMBAL_TORQUE = 0x2704;  // §2.4; mN·m (§2.5)
inline constexpr HDenum HD_LAST_FORCE = 0x2800;             // §2.4
inline constexpr HDenum HD_LAST_TORQUE = 0x2801;            // §2.4
inline constexpr HDenum HD_LAST_GIMBAL_TORQUE = 0x2803;     // §2.4

// ---- Capabilities for hdEnable/hdDisable (§2.4; hdDefines.h 237-243, [OH-REF] Table A-10) ----
inline constexpr HDenum HD_FORCE_OUTPUT = 0x4000;          // §2.4
inline constexpr HDenum HD_MAX_FORCE_CLAMPING = 0x4001;    // §2.4
inline constexpr HDenum HD_FORCE_RAMPING = 0x4002;         // §2.4
inline constexpr HDenum HD_SOFTWARE_FORCE_LIMIT = 0x4003;  // §2.4
inline constexpr HDenum HD_ONE_FRAME_LIMIT = 0x4004;       // §2.4

// ---- Calibration (§2.4; hdDefines.h 259-266) ----
inline constexpr HDenum HD_CALIBRATION_OK = 0x5000;                  // §2.4
inline constexpr HDenum HD_CALIBRATION_NEEDS_UPDATE = 0x5001;        // §2.4
inline constexpr HDenum HD_CALIBRATION_NEEDS_MANUAL_INPUT = 0x5002;  // §2.4 (never returned)
inline constexpr HDint HD_CALIBRATION_ENCODER_RESET = 1;             // §2.4
inline constexpr HDint HD_CALIBRATION_AUTO = 2;                      // §2.4
inline constexpr HDint HD_CALIBRATION_INKWELL = 4;                   // §2.4

// ---- Buttons (§2.4; hdDefines.h 269-272) ----
inline constexpr HDint HD_DEVICE_BUTTON_1 = 1;  // §2.4
inline constexpr HDint HD_DEVICE_BUTTON_2 = 2;  // §2.4
inline constexpr HDint HD_DEVICE_BUTTON_3 = 4;  // §2.4
inline constexpr HDint HD_DEVICE_BUTTON_4 = 8;  // §2.4

// ---- The default scheduler rate (§2.3, [OH-PG] p.1-12: "the default 1000 Hz rate") ----
inline constexpr HDulong kDefaultSchedulerRate = 1000;

// ---- Function pointer types: the C signatures of §2.3 ([OH] hdDevice.h / hdScheduler.h), with
// the types of §2.2. The library checks its definitions against these with static_assert, and the
// test calls through them. ----
using hdInitDevice_t = HHD (*)(HDstring pConfigName);            // hdDevice.h 35
using hdMakeCurrentDevice_t = void (*)(HHD hHD);                 // 39
using hdDisableDevice_t = void (*)(HHD hHD);                     // 42
using hdGetCurrentDevice_t = HHD (*)();                          // 45
using hdBeginFrame_t = void (*)(HHD hHD);                        // 50
using hdEndFrame_t = void (*)(HHD hHD);                          // 51
using hdGetError_t = HDErrorInfo (*)();                          // 53-55
using hdGetErrorString_t = HDstring (*)(HDerror errorCode);      // 59
using hdEnable_t = void (*)(HDenum cap);                         // 63
using hdDisable_t = void (*)(HDenum cap);                        // 64
using hdIsEnabled_t = HDboolean (*)(HDenum cap);                 // 65
using hdGetBooleanv_t = void (*)(HDenum pname, HDboolean* params);  // 69
using hdGetIntegerv_t = void (*)(HDenum pname, HDint* params);      // 70
using hdGetFloatv_t = void (*)(HDenum pname, HDfloat* params);      // 71
using hdGetDoublev_t = void (*)(HDenum pname, HDdouble* params);    // 72
using hdGetLongv_t = void (*)(HDenum pname, HDlong* params);        // 73
using hdGetString_t = HDstring (*)(HDenum pname);                   // 74
using hdSetBooleanv_t = void (*)(HDenum pname, const HDboolean* params);  // 78
using hdSetIntegerv_t = void (*)(HDenum pname, const HDint* params);      // 79
using hdSetFloatv_t = void (*)(HDenum pname, const HDfloat* params);      // 80
using hdSetDoublev_t = void (*)(HDenum pname, const HDdouble* params);    // 81
using hdSetLongv_t = void (*)(HDenum pname, const HDlong* params);        // 82
using hdCheckCalibration_t = HDenum (*)();                       // 85
using hdCheckCalibrationStyle_t = HDenum (*)();                  // 86
using hdUpdateCalibration_t = void (*)(HDenum style);            // 88
using hdStartScheduler_t = void (*)();                           // hdScheduler.h 55
using hdStopScheduler_t = void (*)();                            // 56
using hdSetSchedulerRate_t = void (*)(HDulong nRate);            // 57
using hdScheduleSynchronous_t = void (*)(HDSchedulerCallback pCallback, void* pUserData,
                                         HDushort nPriority);    // 65-67
using hdScheduleAsynchronous_t = HDSchedulerHandle (*)(HDSchedulerCallback pCallback,
                                                       void* pUserData,
                                                       HDushort nPriority);  // 71-74
using hdUnschedule_t = void (*)(HDSchedulerHandle hHandle);      // 77
using hdWaitForCompletion_t = HDboolean (*)(HDSchedulerHandle hHandle, HDWaitCode param);  // 82-83
using hdGetSchedulerTimeStamp_t = HDdouble (*)();                // 86

// ---- The stand-in's own control API (not part of any vendor runtime) ----
using fake_hd_control_t = int (*)(const char* command);
using fake_hd_calls_t = const char* (*)();
using fake_hd_clear_calls_t = void (*)();
using fake_hd_blocked_t = int (*)();

}  // namespace fake_hd
