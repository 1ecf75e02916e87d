// hapticd's driver for Force Dimension devices (omega.3/.6/.7, sigma.7, delta.3, lambda.7, and the
// Novint Falcon, which Force Dimension's SDK drives too), through the vendor's own runtime, loaded
// at start with dlopen: built against <haptic/driver.h> alone, it needs no SDK to build.
//
// Every declaration of the vendor's API below is written from the public facts collected, with
// their sources, in driver/vendors/SOURCES.md (section 1; "§1.x" below): the C signatures of the
// DHD/DRD API of SDK 3.17.5, its return conventions, constants, units and frames.
//
// The device at its tool point, in W = the DHD device frame: x towards the operator, y to the
// right, z up, origin at the centre of the workspace (§1.6; inferred from CHAI3D, which passes
// dhdGetPosition through unchanged). Units SI: m, m/s, N, N·m, rad (§1.6). hapticd's Cartesian
// model: joints 0..2 are x, y, z; the command's tau[0..2] the force. A wrist's orientation is
// reported (ORIENTATION); an active wrist takes torques (TORQUE_OUTPUT), an active gripper a
// gripping force (GRIPPER).
//
// params (all optional):
//   "library": the runtime to load (a path or a name dlopen searches); default libdrd.so.3,
//              libdrd.so, libdhd.so.3, libdhd.so, then $FDSDK/lib/release/lin-x86_64-gcc/ (§1.1)
//   "index": the device's enumeration index (default 0), or "serial": its serial number
//   "calibrate": true (default): a device in RESET mode is calibrated at start with drdAutoInit,
//              which moves it (§1.3, DRD); false: start refuses an uncalibrated device
//   "gravity_compensation": true (default): the vendor's own, computed on the host (§1.6)
//   "max_force" (N), "workspace_radius" (m): override the model's figures (required for a model
//              this driver does not know)
//   "apparent_mass", "apparent_damping": [x, y, z] (kg, N·s/m): the device at its tool as a
//              mass-damper, from one's own identification; Force Dimension publishes none, so
//              the default is unknown (0), and hapticd's stability report and passivity are off
//   "status_period": reads between two looks at the device's force state (dhdGetStatus),
//              default 1 (every read); a device that turns its forces off is seen within that many
//   "resume_speed": m/s (default 0.1): forces the device or the safe state turned off are turned on
//              again at the first read whose velocity is below this on every axis
//
// The force state. The device may turn its forces off itself (its velocity guard, its watchdog,
// its force button, a dead-man switch: §1.6 "Safety", §1.5 force-off causes) while dhdSetForce
// goes on succeeding. Each read looks at dhdGetStatus (every status_period reads); forces found
// off are a device fault: the reading says safe_state, and last_error names the cause in the SDK's
// words. Forces off for any cause but a person's (the force button, the dead-man switch) are
// turned on again (dhdEnableForce, §1.3) at the first read with the hand slower than resume_speed,
// and a zero force is commanded at once, so that the SDK's gravity compensation, which goes out
// only with a force command (§1.6), holds the arm before the loop's first force; a person's are
// waited for (the status shows forces on again). enter_safe_state turns forces off (BRAKE mode)
// rather than only asking for the brakes, which the SDK's modes do not apply in FORCE mode.
#include <haptic/driver.h>


#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "common/driver_adapter.hpp"
#include "common/vendor_runtime.hpp"

namespace {

// ---- The vendor's API, as declared from SOURCES.md §1.3 (plain C ABI on Linux, §1.2) ----
using ushort = unsigned short;
using uchar = unsigned char;
using uint = unsigned int;

constexpr int kDhdOn = 1;   // DHD_ON  (§1.5)
constexpr int kDhdOff = 0;  // DHD_OFF (§1.5)
constexpr int kMotorSaturated = 2;  // DHD_MOTOR_SATURATED, a setter's success that scaled the command (§1.4)
constexpr int kStatusSize = 32;     // DHD_MAX_STATUS is 17 (16 in 3.7.0): room for more (§1.5)
constexpr int kStatusReset = 3;     // DHD_STATUS_RESET (§1.5)
constexpr int kStatusForce = 5;     // DHD_STATUS_FORCE (§1.5)
constexpr int kStatusForceOffCause = 14;  // DHD_STATUS_FORCEOFFCAUSE (§1.5)

/// Why the device's forces are off, in the SDK's words: the force-off causes of §1.5 (values 0 to
/// 6; DHD_FORCE_OFF_*, spelt DHD_FORCEOFF_* before 3.17) and what this driver does about each.
const char* force_off_words(int cause) {
  switch (cause) {
    case 1:
      return "dhdGetStatus: forces turned off at the device's force button (DHD_FORCE_OFF_BUTTON); "
             "they resume when it is pressed again";
    case 2:
      return "dhdGetStatus: forces turned off by the device's velocity guard, the handle moved faster "
             "than its threshold (DHD_FORCE_OFF_VELOCITY); on again once the hand is slow";
    case 3:
      return "dhdGetStatus: forces turned off by the device's watchdog, no command reached it in time "
             "(DHD_FORCE_OFF_WATCHDOG); on again once the hand is slow";
    case 4:
      return "dhdGetStatus: forces turned off by software (DHD_FORCE_OFF_SOFTWARE); on again once the "
             "hand is slow";
    case 5:
      return "dhdGetStatus: forces turned off, the USB connection was lost (DHD_FORCE_OFF_USBDISCN); on "
             "again once the hand is slow";
    case 6:
      return "dhdGetStatus: forces turned off by the device's dead-man switch (DHD_FORCE_OFF_DEADMAN); "
             "they resume when it is held again";
    case 0:
      return "dhdGetStatus: the device's forces are off with no cause given (DHD_FORCE_OFF_NONE); on "
             "again once the hand is slow";
    default:
      return "dhdGetStatus: the device's forces are off for a cause this driver does not know; on again "
             "once the hand is slow";
  }
}
/// A person turned the forces off (the force button, the dead-man switch): theirs to turn on.
bool by_person(int cause) { return cause == 1 || cause == 6; }

// The runtime's functions as declared from §1.3, one list each: X(return type, name, parameters).
// The symbol is "dhd" + name for the DHD's, the name itself for the DRD's.
#define DHD_REQUIRED(X)                                                    \
  X(int, GetDeviceCount, ())                                               \
  X(int, OpenID, (char id))                                                \
  X(int, OpenSerial, (int serial))                                         \
  X(int, Close, (char id))                                                 \
  X(int, GetSystemType, (char id))                                         \
  X(const char*, GetSystemName, (char id))                                 \
  X(int, GetSerialNumber, (ushort* sn, char id))                           \
  X(int, EnableForce, (uchar val, char id))                                \
  X(int, SetGravityCompensation, (int val, char id))                       \
  X(int, Stop, (char id))                                                  \
  X(int, GetPosition, (double* px, double* py, double* pz, char id))       \
  X(int, GetLinearVelocity, (double* vx, double* vy, double* vz, char id)) \
  X(uint, GetButtonMask, (char id))                                        \
  X(int, SetForce, (double fx, double fy, double fz, char id))             \
  X(int, GetStatus, (int status[kStatusSize], char id))                    \
  X(int, ErrorGetLast, ())                                                 \
  X(const char*, ErrorGetStr, (int error))
// Optional: a device without a wrist or gripper needs none of these, and a runtime without them
// drives such devices (a device that has them is refused at create, naming what is missing).
#define DHD_OPTIONAL(X)                                                                     \
  X(int, GetOrientationFrame, (double matrix[3][3], char id))                               \
  X(int, GetAngularVelocityRad, (double* wx, double* wy, double* wz, char id))              \
  X(int, GetGripperAngleRad, (double* a, char id))                                          \
  X(int, SetForceAndTorqueAndGripperForce,                                                  \
    (double fx, double fy, double fz, double tx, double ty, double tz, double fg, char id)) \
  X(bool, HasWrist, (char id))                                                              \
  X(bool, HasActiveWrist, (char id))                                                        \
  X(bool, HasGripper, (char id))                                                            \
  X(bool, HasActiveGripper, (char id))                                                      \
  X(bool, IsLeftHanded, (char id))
// DRD, in libdrd only (§1.1: libdrd holds every dhd function too); absent with a bare libdhd.
#define DRD_OPTIONAL(X)                \
  X(bool, drdIsSupported, (char id))   \
  X(bool, drdIsInitialized, (char id)) \
  X(int, drdAutoInit, (char id))       \
  X(int, drdStop, (bool frc, char id))

struct DhdApi {
  DHD_REQUIRED(HAPTIC_RUNTIME_FUNCTION)
  DHD_OPTIONAL(HAPTIC_RUNTIME_FUNCTION)
  DRD_OPTIONAL(HAPTIC_RUNTIME_FUNCTION)
};

/// What this driver knows of each model (the type codes of §1.5). Force, workspace radius, torque
/// and gripper figures are CHAI3D's table (§1.7: Force Dimension's product pages were not found);
/// buttons: the Falcon's four (§1.5, "Falcon button indices"), one elsewhere.
struct Model {
  int type;
  const char* name;
  double max_force;         // N
  double workspace_radius;  // m
  double max_torque;        // N·m, active wrists
  double gripper_force;     // N, active grippers
  double gripper_max;       // rad
  unsigned buttons;
};
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr Model kModels[] = {
    {63, "delta.3", 20.0, 0.15, 0.0, 0.0, 0.0, 1},
    {33, "omega.3", 12.0, 0.075, 0.0, 0.0, 0.0, 1},
    {34, "omega.6 (right)", 12.0, 0.075, 0.0, 0.0, 0.0, 1},
    {36, "omega.6 (left)", 12.0, 0.075, 0.0, 0.0, 0.0, 1},
    {35, "omega.7 (right)", 12.0, 0.075, 0.0, 8.0, 30.0 * kDeg, 1},
    {37, "omega.7 (left)", 12.0, 0.075, 0.0, 8.0, 30.0 * kDeg, 1},
    {104, "sigma.7 (right)", 12.0, 0.075, 0.2, 8.0, 30.0 * kDeg, 1},
    {105, "sigma.7 (left)", 12.0, 0.075, 0.2, 8.0, 30.0 * kDeg, 1},
    {108, "lambda.7 (right)", 12.0, 0.1125, 0.2, 8.0, 15.0 * kDeg, 1},
    {109, "lambda.7 (left)", 12.0, 0.1125, 0.2, 8.0, 15.0 * kDeg, 1},
    {60, "Novint Falcon", 8.0, 0.04, 0.0, 0.0, 0.0, 4},
};

/// The models with a wrist (omega.6/.7, sigma.7, lambda.7, either hand; §1.5 type codes), for a
/// runtime without dhdHasWrist.
bool wrist_by_type(int type) {
  for (int wristed : {34, 35, 36, 37, 104, 105, 108, 109}) {
    if (type == wristed) return true;
  }
  return false;
}

const Model* model_of(int type) {
  for (const Model& model : kModels) {
    if (model.type == type) return &model;
  }
  return nullptr;
}

/// Where the runtime is looked for (§1.1) and what to install when it is not there.
haptic::vendor::RuntimeSearch runtime_search() {
  std::vector<std::string> names = {"libdrd.so.3", "libdrd.so", "libdhd.so.3", "libdhd.so"};
  if (const char* sdk = std::getenv("FDSDK")) names.push_back(std::string(sdk) + "/lib/release/lin-x86_64-gcc/libdrd.so");
  return {names, "Force Dimension runtime",
          "install the Force Dimension SDK (its lib/release/lin-*-gcc files; it needs libusb-1.0)"};
}

/// Resolves every function; empty on success, else the first missing required one.
std::string resolve(void* library, DhdApi& api) {
  haptic::vendor::Symbols symbols(library);
#define NEED_DHD(type, name, params) symbols.need(api.name, "dhd" #name);
#define MAY_DHD(type, name, params) symbols.may(api.name, "dhd" #name);
#define MAY_DRD(type, name, params) symbols.may(api.name, #name);
  DHD_REQUIRED(NEED_DHD)
  DHD_OPTIONAL(MAY_DHD)
  DRD_OPTIONAL(MAY_DRD)
#undef NEED_DHD
#undef MAY_DHD
#undef MAY_DRD
  return symbols.missing();
}

/// One device through the runtime: the driver's device (common/driver_adapter.hpp).
struct Device : haptic::vendor::VendorDevice {
  static constexpr const char* kParams[] = {"library",          "index",         "serial",
                                            "calibrate",        "gravity_compensation", "max_force",
                                            "workspace_radius", "apparent_mass", "apparent_damping",
                                            "status_period",    "resume_speed"};
  static constexpr bool kDeviceClocked = false;  // the SDK has no servo callback to hand the loop

  HAPTIC_VENDOR_DEVICE(Device);

  ~Device() {
    if (opened) haptic::vendor::quietly([this] { api.Close(id); });
  }

  haptic::vendor::LoadedLibrary library;  // declared first: closed after the destructor's dhdClose
  DhdApi api;
  bool opened = false;  // `id` names a device this driver opened (closed by the destructor)
  char id = -1;
  int type = 0;
  std::string name;
  ushort serial = 0;
  Model model{};
  bool wrist = false, active_wrist = false, gripper = false, active_gripper = false;
  bool left_handed = false;  // dhdIsLeftHanded: the gripper's angle and force come mirrored (§1.6)
  bool calibrate = true, gravity_compensation = true;
  double apparent_mass[3] = {0, 0, 0}, apparent_damping[3] = {0, 0, 0};
  unsigned status_period = 1;  // reads between looks at dhdGetStatus
  unsigned reads_since_status = 0;
  double resume_speed = 0.1;   // m/s
  std::uint64_t sequence = 0;
  // Forces are off (the device turned them off, a call failed, or enter_safe_state did) and are to
  // be turned on again; set from enter_safe_state's thread too.
  std::atomic<bool> forces_off{false};
  bool person_off = false;  // ... by a person (force button, dead-man switch): theirs to turn on
  // Commands the runtime scaled down (DHD_MOTOR_SATURATED, §1.4): counted, logged at stop.
  std::atomic<std::uint64_t> commands{0}, saturated{0};
  // The most recent failure, for last_error (read off the loop): the vendor's code and the call
  // (code 0: `failed_call` is the whole text, the driver's own words or a force-off cause).
  std::atomic<int> failed_code{0};
  std::atomic<const char*> failed_call{nullptr};

  /// Records a failed call (a negative return, §1.4) for last_error; returns HAPTIC_DRIVER_FAILED.
  int failed(const char* call) {
    forces_off.store(true, std::memory_order_relaxed);  // the SDK may have dropped them (§1.5)
    failed_code.store(api.ErrorGetLast(), std::memory_order_relaxed);
    failed_call.store(call, std::memory_order_release);
    return HAPTIC_DRIVER_FAILED;
  }
  /// Records a fault in the driver's own words (a fixed string).
  void says(const char* words) {
    failed_code.store(0, std::memory_order_relaxed);
    failed_call.store(words, std::memory_order_release);
  }
  /// Commands zero force (and torque, gripper force) at once: the SDK's gravity compensation goes
  /// out with it (§1.6). Returns the setter's result (§1.4); `call` names the setter.
  int command_zero(const char*& call) const {
    if ((active_wrist || active_gripper) && api.SetForceAndTorqueAndGripperForce != nullptr) {
      call = "dhdSetForceAndTorqueAndGripperForce";
      return api.SetForceAndTorqueAndGripperForce(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, id);
    }
    call = "dhdSetForce";
    return api.SetForce(0.0, 0.0, 0.0, id);
  }
};

std::string vendor_error(const DhdApi& api) {
  const int code = api.ErrorGetLast();
  const char* text = api.ErrorGetStr(code);
  return (text != nullptr ? text : "error") + std::string(" (DHD error ") + std::to_string(code) + ")";
}

std::unique_ptr<Device> Device::open(const haptic::vendor::DriverParams& params) {
  using haptic::vendor::Refusal;
  auto device = std::make_unique<Device>();
  {
    device->library = haptic::vendor::open_runtime(params.text("library").value_or(""), runtime_search(),
                                                   device->api, resolve);
    std::string why;
    DhdApi& api = device->api;
    int opened = -1;
    if (params.has("serial")) {
      const double serial = *params.number("serial");
      opened = api.OpenSerial(static_cast<int>(serial));
      if (opened < 0) why = "params.serial " + std::to_string(static_cast<int>(serial)) + ": " + vendor_error(api);
    } else {
      const double index = params.number("index").value_or(0.0);
      const int count = api.GetDeviceCount();
      if (count <= 0) {
        why = "no Force Dimension device found (" + (count < 0 ? vendor_error(api) : "0 connected") +
              "): is it plugged in and powered, and may this user open it (udev rules, docs/devices.md)?";
      } else if (!(index >= 0 && index < count && index == std::floor(index))) {
        char shown[32];
        std::snprintf(shown, sizeof shown, "%g", index);
        why = "params.index " + std::string(shown) + ": " + std::to_string(count) +
              (count == 1 ? " device connected, index 0" : " devices connected, index 0 to " + std::to_string(count - 1));
      } else {
        opened = api.OpenID(static_cast<char>(index));
        if (opened < 0) why = "opening device " + std::to_string(static_cast<int>(index)) + ": " + vendor_error(api);
      }
    }
    if (opened < 0) throw Refusal(why);
    device->id = static_cast<char>(opened);
    device->opened = true;
    device->type = api.GetSystemType(device->id);
    const char* name = api.GetSystemName(device->id);
    device->name = name != nullptr ? name : "Force Dimension device";
    api.GetSerialNumber(&device->serial, device->id);
    const Model* known = model_of(device->type);
    device->model = known != nullptr ? *known : Model{device->type, "unknown", 0.0, 0.0, 0.0, 0.0, 0.0, 1};
    if (auto f = params.number("max_force")) device->model.max_force = *f;
    if (auto r = params.number("workspace_radius")) device->model.workspace_radius = *r;
    if (!(device->model.max_force > 0.0 && device->model.workspace_radius > 0.0)) {
      throw Refusal("device type " + std::to_string(device->type) + " (" + device->name +
                    ") is not one this driver knows: give params.max_force (N) and "
                    "params.workspace_radius (m) from its manual");
    }
    // A runtime without the equipment queries drives wrist-less devices only.
    device->wrist = api.HasWrist != nullptr ? api.HasWrist(device->id) : wrist_by_type(device->type);
    device->active_wrist = api.HasActiveWrist != nullptr && api.HasActiveWrist(device->id);
    device->gripper = api.HasGripper != nullptr && api.HasGripper(device->id);
    device->active_gripper = api.HasActiveGripper != nullptr && api.HasActiveGripper(device->id);
    device->left_handed = api.IsLeftHanded != nullptr && api.IsLeftHanded(device->id);
    const char* lacking = nullptr;  // the first function the device's wrist or gripper needs
    if (device->wrist && api.GetOrientationFrame == nullptr) {
      lacking = "dhdGetOrientationFrame";
    } else if (device->wrist && api.GetAngularVelocityRad == nullptr) {
      lacking = "dhdGetAngularVelocityRad";
    } else if (device->gripper && api.GetGripperAngleRad == nullptr) {
      lacking = "dhdGetGripperAngleRad";
    } else if ((device->active_wrist || device->active_gripper) && api.SetForceAndTorqueAndGripperForce == nullptr) {
      lacking = "dhdSetForceAndTorqueAndGripperForce";
    }
    if (lacking != nullptr) {
      throw Refusal("the Force Dimension runtime lacks " + std::string(lacking) + ", which the " + device->name +
                    "'s wrist or gripper needs (an SDK older than 3.17?)");
    }
    device->calibrate = params.boolean("calibrate").value_or(true);
    device->gravity_compensation = params.boolean("gravity_compensation").value_or(true);
    if (auto m = params.triple("apparent_mass")) std::copy(m->begin(), m->end(), device->apparent_mass);
    if (auto b = params.triple("apparent_damping")) std::copy(b->begin(), b->end(), device->apparent_damping);
    if (auto n = params.number("status_period")) {
      if (!(*n >= 1.0 && *n <= 1000.0 && *n == std::floor(*n))) {
        throw Refusal("params.status_period: a whole number of reads, 1 to 1000");
      }
      device->status_period = static_cast<unsigned>(*n);
    }
    if (auto v = params.number("resume_speed")) {
      if (!(*v > 0.0 && std::isfinite(*v))) {
        throw Refusal("params.resume_speed: a speed > 0 (m/s)");
      }
      device->resume_speed = *v;
    }
  }
  return device;
}

void Device::describe(haptic_driver_info& info) const {
  std::snprintf(info.name, sizeof info.name, "Force Dimension %s, serial %u", name.c_str(),
                static_cast<unsigned>(serial));
  info.joints = 3;
  info.dof = 3;
  info.buttons = model.buttons;
  info.capabilities = HAPTIC_DRIVER_MEASURED_RATES;  // the SDK's own velocity estimate (§1.5)
  if (wrist) info.capabilities |= HAPTIC_DRIVER_ORIENTATION;
  if (active_wrist && model.max_torque > 0.0) info.capabilities |= HAPTIC_DRIVER_TORQUE_OUTPUT;
  if (active_gripper && model.gripper_force > 0.0) info.capabilities |= HAPTIC_DRIVER_GRIPPER;
  info.max_force = model.max_force;
  for (int i = 0; i < 3; ++i) {
    info.workspace_min[i] = -model.workspace_radius;
    info.workspace_max[i] = model.workspace_radius;
    info.apparent_mass[i] = apparent_mass[i];
    info.apparent_damping[i] = apparent_damping[i];
  }
  info.max_torque = model.max_torque;
  info.gripper_max_force = model.gripper_force;
  info.gripper_min = 0.0;
  info.gripper_max = model.gripper_max;
}

int Device::start() {
  // Calibration (§1.3, DRD): a device in RESET mode is not initialized; drdAutoInit moves it to a
  // known position and resets its encoders, then the robotic controller is stopped (as CHAI3D does).
  // Only a device the DRD supports (drdIsSupported: its regulation is built in) is calibrated so;
  // for another (a Falcon) the status's RESET says whether it must be calibrated by hand.
  const bool drd = api.drdIsInitialized != nullptr && api.drdAutoInit != nullptr &&
                   (api.drdIsSupported == nullptr || api.drdIsSupported(id));
  bool needs_calibration = false;
  if (drd) {
    needs_calibration = !api.drdIsInitialized(id);
  } else {
    int status[kStatusSize] = {};
    if (api.GetStatus(status, id) < 0) return failed("dhdGetStatus");
    needs_calibration = status[kStatusReset] != 0;
  }
  if (needs_calibration) {
    if (!calibrate) {
      say(HAPTIC_DRIVER_LOG_ERROR, "the device is not calibrated and params.calibrate is false");
      says("the device is not calibrated and params.calibrate is false");
      return HAPTIC_DRIVER_FAILED;
    }
    if (!drd) {
      const char* why = "the device is not calibrated (RESET mode) and the DRD cannot calibrate it "
                        "(drdIsSupported: false): calibrate it by hand as its manual says, then start again";
      say(HAPTIC_DRIVER_LOG_ERROR, why);
      says(why);
      return HAPTIC_DRIVER_FAILED;
    }
    say(HAPTIC_DRIVER_LOG_WARNING, "calibrating: the device moves to its reset position (keep clear)");
    if (api.drdAutoInit(id) < 0) return failed("drdAutoInit");
    if (api.drdStop != nullptr) api.drdStop(true, id);
    say(HAPTIC_DRIVER_LOG_INFO, "calibrated");
  }
  if (api.SetGravityCompensation(gravity_compensation ? kDhdOn : kDhdOff, id) < 0) {
    return failed("dhdSetGravityCompensation");
  }
  if (api.EnableForce(kDhdOn, id) < 0) return failed("dhdEnableForce");
  // Zero force at once: the gravity compensation goes out with a command only (§1.6), and until
  // the loop's first write the arm would fall.
  const char* zero_call = nullptr;
  if (command_zero(zero_call) < 0) return failed(zero_call);
  forces_off.store(false);
  person_off = false;
  reads_since_status = 0;
  commands.store(0);
  saturated.store(0);
  failed_code.store(0);
  failed_call.store(nullptr);
  say(HAPTIC_DRIVER_LOG_INFO, "forces enabled on " + name + (gravity_compensation
                                                                              ? ", the SDK's gravity compensation on"
                                                                              : ", gravity compensation off"));
  if (left_handed && gripper) {
    say(HAPTIC_DRIVER_LOG_INFO, "a left-handed device: its gripper's angle and force are mirrored");
  }
  return HAPTIC_DRIVER_OK;
}

void Device::stop() {
  api.SetForce(0.0, 0.0, 0.0, id);
  api.Stop(id);  // forces off, brakes on
  if (const std::uint64_t scaled = saturated.load(); scaled > 0) {
    say(HAPTIC_DRIVER_LOG_WARNING,
        std::to_string(scaled) + " of " + std::to_string(commands.load()) +
            " force commands came back DHD_MOTOR_SATURATED: the device scaled them down (a motor "
            "could not deliver its share), so it applied less than hapticd reported");
  }
}

// Each getter returns 0 or DHD_TIMEGUARD (1) on success, -1 on error (§1.4): success is >= 0.
int Device::read(haptic_driver_reading& reading) {
  reading.safe_state = 0;  // hapticd hands the same reading back each call
  if (api.GetPosition(&reading.q[0], &reading.q[1], &reading.q[2], id) < 0) {
    return failed("dhdGetPosition");
  }
  if (api.GetLinearVelocity(&reading.q_dot[0], &reading.q_dot[1], &reading.q_dot[2], id) < 0) {
    return failed("dhdGetLinearVelocity");
  }
  if (wrist) {
    double matrix[3][3];
    if (api.GetOrientationFrame(matrix, id) < 0) return failed("dhdGetOrientationFrame");
    haptic::vendor::quaternion_of(matrix, reading.orientation_W);  // R(i,j) = matrix[i][j] (§1.6)
    double* w = reading.angular_velocity_W;
    if (api.GetAngularVelocityRad(&w[0], &w[1], &w[2], id) < 0) return failed("dhdGetAngularVelocityRad");
  } else {
    reading.orientation_W[0] = 1.0;
  }
  if (gripper) {
    if (api.GetGripperAngleRad(&reading.gripper, id) < 0) return failed("dhdGetGripperAngleRad");
    if (left_handed) reading.gripper = -reading.gripper;  // negative on a left hand (§1.6)
  }
  reading.buttons = api.GetButtonMask(id);
  reading.sequence = ++sequence;  // each call reads the device afresh
  // The force state, every status_period reads, and every read while forces are off.
  const bool off = forces_off.load(std::memory_order_relaxed);
  if (!off && ++reads_since_status < status_period) return HAPTIC_DRIVER_OK;
  reads_since_status = 0;
  int status[kStatusSize] = {};
  if (api.GetStatus(status, id) < 0) return failed("dhdGetStatus");
  const bool on = status[kStatusForce] != 0;
  if (!off) {
    if (on) return HAPTIC_DRIVER_OK;
    // The device turned them off itself while its setters went on succeeding.
    const int cause = status[kStatusForceOffCause];
    person_off = by_person(cause);
    forces_off.store(true, std::memory_order_relaxed);
    says(force_off_words(cause));
    reading.safe_state = 1;
    return HAPTIC_DRIVER_OK;
  }
  // Forces are off: a person's are theirs to turn on; others are turned on once the hand is slow.
  if (person_off) {
    if (!on) {
      reading.safe_state = 1;
      return HAPTIC_DRIVER_OK;
    }
  } else {
    for (int i = 0; i < 3; ++i) {
      if (!(std::fabs(reading.q_dot[i]) < resume_speed)) {
        reading.safe_state = 1;
        return HAPTIC_DRIVER_OK;
      }
    }
    if (api.EnableForce(kDhdOn, id) < 0) return failed("dhdEnableForce");
  }
  const char* zero_call = nullptr;
  if (command_zero(zero_call) < 0) return failed(zero_call);  // zero first
  person_off = false;
  forces_off.store(false, std::memory_order_relaxed);
  return HAPTIC_DRIVER_OK;
}

// The setters return 0 or DHD_MOTOR_SATURATED (2) on success, -1 on error (§1.4).
int Device::write(const haptic_driver_command& command, double /*dt*/) {
  const double* f = command.tau;
  int result;
  if (active_wrist || active_gripper) {
    const double* t = command.torque_W;
    // A left-handed device's gripper force is mirrored as its angle is (CHAI3D negates both, §1.6).
    const double fg = active_gripper ? (left_handed ? -1.0 : 1.0) * command.gripper_force : 0.0;
    result = api.SetForceAndTorqueAndGripperForce(f[0], f[1], f[2], active_wrist ? t[0] : 0.0,
                                                  active_wrist ? t[1] : 0.0,
                                                  active_wrist ? t[2] : 0.0, fg, id);
    if (result < 0) return failed("dhdSetForceAndTorqueAndGripperForce");
  } else {
    result = api.SetForce(f[0], f[1], f[2], id);
    if (result < 0) return failed("dhdSetForce");
  }
  commands.fetch_add(1, std::memory_order_relaxed);
  if (result == kMotorSaturated) saturated.fetch_add(1, std::memory_order_relaxed);
  return HAPTIC_DRIVER_OK;
}

// Forces off, which puts the device in BRAKE mode ([FDC-DOCS] Device Modes); dhdSetBrakes alone
// leaves a device in FORCE mode. The DHD API is thread-safe ([FDC-DOCS] Threading), so this may
// run beside a hung read. The next read with the hand slow turns them on again, zero force first.
void Device::enter_safe_state() {
  forces_off.store(true, std::memory_order_relaxed);
  api.SetForce(0.0, 0.0, 0.0, id);
  api.EnableForce(kDhdOff, id);
}

int Device::list_devices(const haptic::vendor::DriverParams& params, std::string& out) {
  DhdApi api;
  const haptic::vendor::LoadedLibrary library =
      haptic::vendor::open_runtime(params.text("library").value_or(""), runtime_search(), api, resolve);
  const int count = api.GetDeviceCount();
  if (count < 0) {
    out = "dhdGetDeviceCount: " + vendor_error(api);
    return -1;
  }
  for (int index = 0; index < count; ++index) {
    const int id = api.OpenID(static_cast<char>(index));
    std::string description = "(in use or unreadable: " + vendor_error(api) + ")";
    if (id >= 0) {
      ushort serial = 0;
      api.GetSerialNumber(&serial, static_cast<char>(id));
      const char* name = api.GetSystemName(static_cast<char>(id));
      description = std::string("Force Dimension ") + (name != nullptr ? name : "device") + ", serial " +
                    std::to_string(serial);
      api.Close(static_cast<char>(id));
    }
    out += "{\"index\": " + std::to_string(index) + "}\t" + description + "\n";
  }
  return count;
}

void Device::last_error(char* error) const {
  const char* call = failed_call.load(std::memory_order_acquire);
  if (call == nullptr) {
    error[0] = '\0';
    return;
  }
  const int code = failed_code.load(std::memory_order_relaxed);
  if (code == 0) {  // this driver's own words (a refusal, a force-off cause), not a runtime error
    std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", call);
    return;
  }
  const char* text = api.ErrorGetStr(code);  // a fixed string of the runtime's
  std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s: %s (DHD error %d)", call,
                text != nullptr ? text : "error", code);
}

}  // namespace

HAPTIC_VENDOR_DRIVER(Device)
