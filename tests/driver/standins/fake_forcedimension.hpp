// The stand-in Force Dimension runtime (libdrd.so.3 built from fake_forcedimension.cpp): the
// project's own declarations of the facts it needs, shared by the library and its unit test.
// Every vendor value is written from driver/vendors/SOURCES.md section 1, and the comment beside it
// names the section and the original source it cites. No vendor header is used or copied.
#pragma once

namespace fake_dhd {

// ---- Return values (SOURCES.md §1.4; [CHAI-DHD] dhdc.h lines 159-161) ----
inline constexpr int DHD_TIMEGUARD = 1;        // §1.4, dhdc.h 159-161 (never returned here)
inline constexpr int DHD_MOTOR_SATURATED = 2;  // §1.4, dhdc.h 159-161

// ---- Error codes (§1.5; [CHAI-DHD] dhdc.h lines 51-75, [FDC] constants.py 68-94) ----
inline constexpr int DHD_NO_ERROR = 0;                  // §1.5, dhdc.h 51
inline constexpr int DHD_ERROR = 1;                     // §1.5
inline constexpr int DHD_ERROR_COM = 2;                 // §1.5
inline constexpr int DHD_ERROR_DHC_BUSY = 3;            // §1.5
inline constexpr int DHD_ERROR_NO_DRIVER_FOUND = 4;     // §1.5
inline constexpr int DHD_ERROR_NO_DEVICE_FOUND = 5;     // §1.5
inline constexpr int DHD_ERROR_NOT_AVAILABLE = 6;       // §1.5
inline constexpr int DHD_ERROR_TIMEOUT = 7;             // §1.5
inline constexpr int DHD_ERROR_GEOMETRY = 8;            // §1.5
inline constexpr int DHD_ERROR_EXPERT_MODE_DISABLED = 9;  // §1.5
inline constexpr int DHD_ERROR_NOT_IMPLEMENTED = 10;    // §1.5
inline constexpr int DHD_ERROR_OUT_OF_MEMORY = 11;      // §1.5
inline constexpr int DHD_ERROR_DEVICE_NOT_READY = 12;   // §1.5
inline constexpr int DHD_ERROR_FILE_NOT_FOUND = 13;     // §1.5
inline constexpr int DHD_ERROR_CONFIGURATION = 14;      // §1.5
inline constexpr int DHD_ERROR_INVALID_INDEX = 15;      // §1.5
inline constexpr int DHD_ERROR_DEPRECATED = 16;         // §1.5
inline constexpr int DHD_ERROR_NULL_ARGUMENT = 17;      // §1.5
inline constexpr int DHD_ERROR_REDUNDANT_FAIL = 18;     // §1.5
inline constexpr int DHD_ERROR_NOT_ENABLED = 19;        // §1.5
inline constexpr int DHD_ERROR_DEVICE_IN_USE = 20;      // §1.5
inline constexpr int DHD_ERROR_INVALID = 21;            // §1.5
inline constexpr int DHD_ERROR_NO_REGULATION = 22;      // §1.5, dhdc.h 75 (absent in SDK 3.7.0)
inline constexpr int kErrorCount = 23;                  // codes 0..22 above

// ---- Device types (§1.5; [CHAI-DHD] dhdc.h lines 88-106) ----
inline constexpr int DHD_DEVICE_NONE = 0;             // §1.5
inline constexpr int DHD_DEVICE_DELTA3 = 63;          // §1.5
inline constexpr int DHD_DEVICE_OMEGA3 = 33;          // §1.5
inline constexpr int DHD_DEVICE_OMEGA6_RIGHT = 34;    // §1.5
inline constexpr int DHD_DEVICE_OMEGA7_RIGHT = 35;    // §1.5
inline constexpr int DHD_DEVICE_OMEGA7_LEFT = 37;     // §1.5
inline constexpr int DHD_DEVICE_SIGMA7_RIGHT = 104;   // §1.5
inline constexpr int DHD_DEVICE_SIGMA7_LEFT = 105;    // §1.5
inline constexpr int DHD_DEVICE_LAMBDA7_RIGHT = 108;  // §1.5
inline constexpr int DHD_DEVICE_FALCON = 60;          // §1.5

// ---- Switches (§1.5; dhdc.h lines 128-130) ----
inline constexpr int DHD_ON = 1;   // §1.5
inline constexpr int DHD_OFF = 0;  // §1.5

// ---- Status vector (§1.5; dhdc.h line 164 and lines 167-183) ----
inline constexpr int DHD_MAX_STATUS = 17;  // §1.5, dhdc.h 164 (16 in SDK 3.7.0)
inline constexpr int DHD_STATUS_POWER = 0;            // §1.5
inline constexpr int DHD_STATUS_CONNECTED = 1;        // §1.5
inline constexpr int DHD_STATUS_STARTED = 2;          // §1.5
inline constexpr int DHD_STATUS_RESET = 3;            // §1.5
inline constexpr int DHD_STATUS_IDLE = 4;             // §1.5
inline constexpr int DHD_STATUS_FORCE = 5;            // §1.5
inline constexpr int DHD_STATUS_BRAKE = 6;            // §1.5
inline constexpr int DHD_STATUS_TORQUE = 7;           // §1.5
inline constexpr int DHD_STATUS_WRIST_DETECTED = 8;   // §1.5
inline constexpr int DHD_STATUS_ERROR = 9;            // §1.5
inline constexpr int DHD_STATUS_GRAVITY = 10;         // §1.5
inline constexpr int DHD_STATUS_TIMEGUARD = 11;       // §1.5
inline constexpr int DHD_STATUS_WRIST_INIT = 12;      // §1.5
inline constexpr int DHD_STATUS_REDUNDANCY = 13;      // §1.5
inline constexpr int DHD_STATUS_FORCE_OFF_CAUSE = 14;  // §1.5
inline constexpr int DHD_STATUS_LOCKS = 15;           // §1.5 (1/0/-1 unknown, [FDC] containers)
inline constexpr int DHD_STATUS_AXIS_CHECKED = 16;    // §1.5

// ---- Force-off causes (§1.5; dhdc.h lines 200-206) ----
inline constexpr int DHD_FORCE_OFF_NONE = 0;      // §1.5
inline constexpr int DHD_FORCE_OFF_BUTTON = 1;    // §1.5
inline constexpr int DHD_FORCE_OFF_VELOCITY = 2;  // §1.5
inline constexpr int DHD_FORCE_OFF_WATCHDOG = 3;  // §1.5
inline constexpr int DHD_FORCE_OFF_SOFTWARE = 4;  // §1.5
inline constexpr int DHD_FORCE_OFF_USBDISCN = 5;  // §1.5
inline constexpr int DHD_FORCE_OFF_DEADMAN = 6;   // §1.5

inline constexpr int DHD_MAX_BUTTONS = 32;  // §1.5, dhdc.h 186 (16 in SDK 3.7.0)

// §1.6, [FDC] dhd/__init__.py ~1307-1339: the SDK's standard gravity by default. Unit: m/s².
inline constexpr double kStandardGravity = 9.81;

// ---- The SDK version the stand-in reports (§1.3: "DHD - Haptic SDK ver 3.17.5", dhdc.h line 3;
// the revision is not given anywhere, 0 is the stand-in's choice) ----
inline constexpr int kSdkMajor = 3, kSdkMinor = 17, kSdkRelease = 5, kSdkRevision = 0;

// §1.6, [SAW] mtsForceDimension.cpp lines 655-658: dhdGetSerialNumber on a Falcon gives 65535.
inline constexpr unsigned short kFalconSerial = 65535;
inline constexpr int kFirstSerial = 1001;  // the stand-in's own numbering (1001, 1002, ...)

// ---- Function pointer types: the C signatures of §1.3 as seen on Linux (no calling-convention
// attribute, §1.2; `char ID`, -1 = the default device; uchar/ushort/uint as in §1.2). The library
// checks its definitions against these with static_assert, and the test calls through them. ----
using uchar = unsigned char;    // §1.2, [CHAI-DHD] dhdc.h 40-43
using ushort = unsigned short;  // §1.2
using uint = unsigned int;      // §1.2

using dhdGetDeviceCount_t = int (*)();
using dhdGetAvailableCount_t = int (*)();
using dhdOpen_t = int (*)();
using dhdOpenID_t = int (*)(char ID);
using dhdOpenSerial_t = int (*)(int serial);
using dhdOpenType_t = int (*)(int type);
using dhdClose_t = int (*)(char ID);
using dhdSetDevice_t = int (*)(char ID);
using dhdGetDeviceID_t = int (*)();
using dhdGetSystemType_t = int (*)(char ID);
using dhdGetSystemName_t = const char* (*)(char ID);
using dhdGetSerialNumber_t = int (*)(ushort* sn, char ID);
using dhdGetSDKVersion_t = void (*)(int* major, int* minor, int* release, int* revision);
using dhdEnableForce_t = int (*)(uchar val, char ID);
using dhdSetGravityCompensation_t = int (*)(int val, char ID);
using dhdSetBrakes_t = int (*)(int val, char ID);
using dhdStop_t = int (*)(char ID);
using dhdGetPosition_t = int (*)(double* px, double* py, double* pz, char ID);
using dhdGetLinearVelocity_t = int (*)(double* vx, double* vy, double* vz, char ID);
using dhdGetOrientationFrame_t = int (*)(double matrix[3][3], char ID);
using dhdGetPositionAndOrientationFrame_t = int (*)(double* px, double* py, double* pz,
                                                    double matrix[3][3], char ID);
using dhdGetAngularVelocityRad_t = int (*)(double* wx, double* wy, double* wz, char ID);
using dhdGetGripperAngleRad_t = int (*)(double* a, char ID);
using dhdGetGripperAngleDeg_t = int (*)(double* a, char ID);
using dhdGetButtonMask_t = uint (*)(char ID);
using dhdGetButton_t = int (*)(int index, char ID);
using dhdSetForce_t = int (*)(double fx, double fy, double fz, char ID);
using dhdSetForceAndTorque_t = int (*)(double fx, double fy, double fz, double tx, double ty,
                                       double tz, char ID);
using dhdSetForceAndGripperForce_t = int (*)(double fx, double fy, double fz, double fg, char ID);
using dhdSetForceAndTorqueAndGripperForce_t = int (*)(double fx, double fy, double fz, double tx,
                                                      double ty, double tz, double fg, char ID);
using dhdGetForceAndTorqueAndGripperForce_t = int (*)(double* fx, double* fy, double* fz,
                                                      double* tx, double* ty, double* tz,
                                                      double* fg, char ID);
using dhdHasWrist_t = bool (*)(char ID);
using dhdHasActiveWrist_t = bool (*)(char ID);
using dhdHasGripper_t = bool (*)(char ID);
using dhdHasActiveGripper_t = bool (*)(char ID);
using dhdIsLeftHanded_t = bool (*)(char ID);
using dhdGetStatus_t = int (*)(int status[DHD_MAX_STATUS], char ID);
using dhdErrorGetLast_t = int (*)();
using dhdErrorGetLastStr_t = const char* (*)();
using dhdErrorGetStr_t = const char* (*)(int error);
using dhdGetTime_t = double (*)();
using dhdSleep_t = void (*)(double sec);
using drdOpen_t = int (*)();
using drdOpenID_t = int (*)(char ID);
using drdClose_t = int (*)(char ID);
using drdIsSupported_t = bool (*)(char ID);
using drdIsInitialized_t = bool (*)(char ID);
using drdAutoInit_t = int (*)(char ID);
using drdStop_t = int (*)(bool frc, char ID);

// ---- The stand-in's own control API (not part of any vendor runtime) ----
using fake_dhd_control_t = int (*)(const char* command);
using fake_dhd_calls_t = const char* (*)();
using fake_dhd_clear_calls_t = void (*)();
using fake_dhd_blocked_t = int (*)();

}  // namespace fake_dhd
