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
#include <haptic/driver.h>

#include <dlfcn.h>

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

#include "common/driver_params.hpp"
#include "common/vendor_runtime.hpp"

namespace {

// ---- The vendor's API, as declared from SOURCES.md §1.3 (plain C ABI on Linux, §1.2) ----
using ushort = unsigned short;
using uchar = unsigned char;
using uint = unsigned int;

constexpr int kDhdOn = 1;   // DHD_ON  (§1.5)
constexpr int kDhdOff = 0;  // DHD_OFF (§1.5)

struct DhdApi {
  int (*GetDeviceCount)() = nullptr;
  int (*OpenID)(char id) = nullptr;
  int (*OpenSerial)(int serial) = nullptr;
  int (*Close)(char id) = nullptr;
  int (*GetSystemType)(char id) = nullptr;
  const char* (*GetSystemName)(char id) = nullptr;
  int (*GetSerialNumber)(ushort* sn, char id) = nullptr;
  int (*EnableForce)(uchar val, char id) = nullptr;
  int (*SetGravityCompensation)(int val, char id) = nullptr;
  int (*SetBrakes)(int val, char id) = nullptr;
  int (*Stop)(char id) = nullptr;
  int (*GetPosition)(double* px, double* py, double* pz, char id) = nullptr;
  int (*GetLinearVelocity)(double* vx, double* vy, double* vz, char id) = nullptr;
  int (*GetOrientationFrame)(double matrix[3][3], char id) = nullptr;
  int (*GetAngularVelocityRad)(double* wx, double* wy, double* wz, char id) = nullptr;
  int (*GetGripperAngleRad)(double* a, char id) = nullptr;
  uint (*GetButtonMask)(char id) = nullptr;
  int (*SetForce)(double fx, double fy, double fz, char id) = nullptr;
  int (*SetForceAndTorqueAndGripperForce)(double fx, double fy, double fz, double tx, double ty,
                                          double tz, double fg, char id) = nullptr;
  bool (*HasWrist)(char id) = nullptr;
  bool (*HasActiveWrist)(char id) = nullptr;
  bool (*HasGripper)(char id) = nullptr;
  bool (*HasActiveGripper)(char id) = nullptr;
  int (*ErrorGetLast)() = nullptr;
  const char* (*ErrorGetStr)(int error) = nullptr;
  // DRD, in libdrd only (§1.1: libdrd holds every dhd function too); absent with a bare libdhd.
  bool (*drdIsInitialized)(char id) = nullptr;
  int (*drdAutoInit)(char id) = nullptr;
  int (*drdStop)(bool frc, char id) = nullptr;
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

const Model* model_of(int type) {
  for (const Model& model : kModels) {
    if (model.type == type) return &model;
  }
  return nullptr;
}

/// Loads the runtime: `wanted`, or the default names of §1.1. Empty `error` on success.
void* load_runtime(const std::string& wanted, std::string& error) {
  std::vector<std::string> names = {"libdrd.so.3", "libdrd.so", "libdhd.so.3", "libdhd.so"};
  if (const char* sdk = std::getenv("FDSDK")) names.push_back(std::string(sdk) + "/lib/release/lin-x86_64-gcc/libdrd.so");
  return haptic::vendor::load_runtime(wanted, names, "Force Dimension runtime",
                                      "install the Force Dimension SDK (its lib/release/lin-*-gcc files; "
                                      "it needs libusb-1.0)",
                                      error);
}

/// Resolves every function; empty on success, else the first missing one.
std::string resolve(void* library, DhdApi& api) {
  haptic::vendor::Symbols symbols(library);
  auto need = [&symbols](auto& slot, const char* name) { symbols.need(slot, name); };
  need(api.GetDeviceCount, "dhdGetDeviceCount");
  need(api.OpenID, "dhdOpenID");
  need(api.OpenSerial, "dhdOpenSerial");
  need(api.Close, "dhdClose");
  need(api.GetSystemType, "dhdGetSystemType");
  need(api.GetSystemName, "dhdGetSystemName");
  need(api.GetSerialNumber, "dhdGetSerialNumber");
  need(api.EnableForce, "dhdEnableForce");
  need(api.SetGravityCompensation, "dhdSetGravityCompensation");
  need(api.SetBrakes, "dhdSetBrakes");
  need(api.Stop, "dhdStop");
  need(api.GetPosition, "dhdGetPosition");
  need(api.GetLinearVelocity, "dhdGetLinearVelocity");
  need(api.GetOrientationFrame, "dhdGetOrientationFrame");
  need(api.GetAngularVelocityRad, "dhdGetAngularVelocityRad");
  need(api.GetGripperAngleRad, "dhdGetGripperAngleRad");
  need(api.GetButtonMask, "dhdGetButtonMask");
  need(api.SetForce, "dhdSetForce");
  need(api.SetForceAndTorqueAndGripperForce, "dhdSetForceAndTorqueAndGripperForce");
  need(api.HasWrist, "dhdHasWrist");
  need(api.HasActiveWrist, "dhdHasActiveWrist");
  need(api.HasGripper, "dhdHasGripper");
  need(api.HasActiveGripper, "dhdHasActiveGripper");
  need(api.ErrorGetLast, "dhdErrorGetLast");
  need(api.ErrorGetStr, "dhdErrorGetStr");
  // Optional: calibration needs libdrd.
  symbols.may(api.drdIsInitialized, "drdIsInitialized");
  symbols.may(api.drdAutoInit, "drdAutoInit");
  symbols.may(api.drdStop, "drdStop");
  return symbols.missing();
}

struct Device {
  void* library = nullptr;
  DhdApi api;
  char id = -1;
  int type = 0;
  std::string name;
  ushort serial = 0;
  Model model{};
  bool wrist = false, active_wrist = false, gripper = false, active_gripper = false;
  bool calibrate = true, gravity_compensation = true;
  double apparent_mass[3] = {0, 0, 0}, apparent_damping[3] = {0, 0, 0};
  std::uint64_t sequence = 0;
  bool faulted = false;  // a call failed: forces are enabled again once the device answers
  // The most recent failure, for last_error (read off the loop): the vendor's code and the call.
  std::atomic<int> failed_code{0};
  std::atomic<const char*> failed_call{nullptr};
  haptic_driver_log_fn log = nullptr;
  void* log_context = nullptr;

  void say(int level, const std::string& message) const {
    if (log != nullptr) log(log_context, level, message.c_str());
  }
  /// Records a failed call (a negative return, §1.4) for last_error; returns HAPTIC_DRIVER_FAILED.
  int failed(const char* call) {
    faulted = true;
    failed_code.store(api.ErrorGetLast(), std::memory_order_relaxed);
    failed_call.store(call, std::memory_order_release);
    return HAPTIC_DRIVER_FAILED;
  }
};

std::string vendor_error(const DhdApi& api) {
  const int code = api.ErrorGetLast();
  const char* text = api.ErrorGetStr(code);
  return (text != nullptr ? text : "error") + std::string(" (DHD error ") + std::to_string(code) + ")";
}

/// The params this driver takes (header comment), refusing any other.
haptic::vendor::DriverParams read_params(const char* params_json) {
  return haptic::vendor::DriverParams(params_json, {"library", "index", "serial", "calibrate",
                                                    "gravity_compensation", "max_force", "workspace_radius",
                                                    "apparent_mass", "apparent_damping"});
}

void* create(const char* params_json, char* error) {
  auto refuse = [error](const std::string& why) -> void* {
    std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", why.c_str());
    return nullptr;
  };
  try {
    const haptic::vendor::DriverParams params = read_params(params_json);
    auto device = std::make_unique<Device>();
    std::string why;
    device->library = load_runtime(params.text("library").value_or(""), why);
    if (device->library == nullptr) return refuse(why);
    if (const std::string missing = resolve(device->library, device->api); !missing.empty()) {
      dlclose(device->library);
      return refuse("the Force Dimension runtime lacks " + missing + " (an SDK older than 3.17?)");
    }
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
    if (opened < 0) {
      dlclose(device->library);
      return refuse(why);
    }
    device->id = static_cast<char>(opened);
    device->type = api.GetSystemType(device->id);
    const char* name = api.GetSystemName(device->id);
    device->name = name != nullptr ? name : "Force Dimension device";
    api.GetSerialNumber(&device->serial, device->id);
    const Model* known = model_of(device->type);
    device->model = known != nullptr ? *known : Model{device->type, "unknown", 0.0, 0.0, 0.0, 0.0, 0.0, 1};
    if (auto f = params.number("max_force")) device->model.max_force = *f;
    if (auto r = params.number("workspace_radius")) device->model.workspace_radius = *r;
    if (!(device->model.max_force > 0.0 && device->model.workspace_radius > 0.0)) {
      api.Close(device->id);
      dlclose(device->library);
      return refuse("device type " + std::to_string(device->type) + " (" + device->name +
                    ") is not one this driver knows: give params.max_force (N) and "
                    "params.workspace_radius (m) from its manual");
    }
    device->wrist = api.HasWrist(device->id);
    device->active_wrist = api.HasActiveWrist(device->id);
    device->gripper = api.HasGripper(device->id);
    device->active_gripper = api.HasActiveGripper(device->id);
    device->calibrate = params.boolean("calibrate").value_or(true);
    device->gravity_compensation = params.boolean("gravity_compensation").value_or(true);
    if (auto m = params.triple("apparent_mass")) std::copy(m->begin(), m->end(), device->apparent_mass);
    if (auto b = params.triple("apparent_damping")) std::copy(b->begin(), b->end(), device->apparent_damping);
    return device.release();
  } catch (const std::exception& failure) {
    return refuse(failure.what());
  }
}

void destroy(void* driver) {
  auto* device = static_cast<Device*>(driver);
  device->api.Close(device->id);
  dlclose(device->library);
  delete device;
}

int describe(void* driver, haptic_driver_info* info) {
  const auto* device = static_cast<const Device*>(driver);
  std::memset(info, 0, sizeof *info);
  std::snprintf(info->name, sizeof info->name, "Force Dimension %s, serial %u", device->name.c_str(),
                static_cast<unsigned>(device->serial));
  info->joints = 3;
  info->dof = 3;
  info->buttons = device->model.buttons;
  info->capabilities = HAPTIC_DRIVER_MEASURED_RATES;  // the SDK's own velocity estimate (§1.5)
  if (device->wrist) info->capabilities |= HAPTIC_DRIVER_ORIENTATION;
  if (device->active_wrist && device->model.max_torque > 0.0) info->capabilities |= HAPTIC_DRIVER_TORQUE_OUTPUT;
  if (device->active_gripper && device->model.gripper_force > 0.0) info->capabilities |= HAPTIC_DRIVER_GRIPPER;
  info->max_force = device->model.max_force;
  for (int i = 0; i < 3; ++i) {
    info->workspace_min[i] = -device->model.workspace_radius;
    info->workspace_max[i] = device->model.workspace_radius;
    info->apparent_mass[i] = device->apparent_mass[i];
    info->apparent_damping[i] = device->apparent_damping[i];
  }
  info->max_torque = device->model.max_torque;
  info->gripper_max_force = device->model.gripper_force;
  info->gripper_min = 0.0;
  info->gripper_max = device->model.gripper_max;
  return HAPTIC_DRIVER_OK;
}

int start(void* driver) {
  auto* device = static_cast<Device*>(driver);
  DhdApi& api = device->api;
  // Calibration (§1.3, DRD): a device in RESET mode is not initialized; drdAutoInit moves it to a
  // known position and resets its encoders, then the robotic controller is stopped (as CHAI3D does).
  if (api.drdIsInitialized != nullptr && !api.drdIsInitialized(device->id)) {
    if (!device->calibrate) {
      device->say(HAPTIC_DRIVER_LOG_ERROR, "the device is not calibrated and params.calibrate is false");
      device->failed_code.store(0);
      device->failed_call.store("the device is not calibrated and params.calibrate is false");
      return HAPTIC_DRIVER_FAILED;
    }
    device->say(HAPTIC_DRIVER_LOG_WARNING, "calibrating: the device moves to its reset position (keep clear)");
    if (api.drdAutoInit == nullptr || api.drdAutoInit(device->id) < 0) return device->failed("drdAutoInit");
    if (api.drdStop != nullptr) api.drdStop(true, device->id);
    device->say(HAPTIC_DRIVER_LOG_INFO, "calibrated");
  }
  if (api.SetGravityCompensation(device->gravity_compensation ? kDhdOn : kDhdOff, device->id) < 0) {
    return device->failed("dhdSetGravityCompensation");
  }
  if (api.EnableForce(kDhdOn, device->id) < 0) return device->failed("dhdEnableForce");
  device->failed_code.store(0);
  device->failed_call.store(nullptr);
  device->say(HAPTIC_DRIVER_LOG_INFO, "forces enabled on " + device->name + (device->gravity_compensation
                                                                              ? ", the SDK's gravity compensation on"
                                                                              : ", gravity compensation off"));
  return HAPTIC_DRIVER_OK;
}

void stop(void* driver) {
  auto* device = static_cast<Device*>(driver);
  device->api.SetForce(0.0, 0.0, 0.0, device->id);
  device->api.Stop(device->id);  // forces off, brakes on
}

// Each getter returns 0 or DHD_TIMEGUARD (1) on success, -1 on error (§1.4): success is >= 0.
int read_sensors(void* driver, haptic_driver_reading* reading) {
  auto* device = static_cast<Device*>(driver);
  const DhdApi& api = device->api;
  const char id = device->id;
  if (api.GetPosition(&reading->q[0], &reading->q[1], &reading->q[2], id) < 0) {
    return device->failed("dhdGetPosition");
  }
  if (api.GetLinearVelocity(&reading->q_dot[0], &reading->q_dot[1], &reading->q_dot[2], id) < 0) {
    return device->failed("dhdGetLinearVelocity");
  }
  if (device->wrist) {
    double matrix[3][3];
    if (api.GetOrientationFrame(matrix, id) < 0) return device->failed("dhdGetOrientationFrame");
    haptic::vendor::quaternion_of(matrix, reading->orientation_W);  // R(i,j) = matrix[i][j] (§1.6)
    double* w = reading->angular_velocity_W;
    if (api.GetAngularVelocityRad(&w[0], &w[1], &w[2], id) < 0) return device->failed("dhdGetAngularVelocityRad");
  } else {
    reading->orientation_W[0] = 1.0;
  }
  if (device->gripper && api.GetGripperAngleRad(&reading->gripper, id) < 0) {
    return device->failed("dhdGetGripperAngleRad");
  }
  reading->buttons = api.GetButtonMask(id);
  // Back after a failure (a device plugged in again): the SDK leaves its forces off until asked.
  if (device->faulted) {
    if (api.EnableForce(kDhdOn, id) < 0) return device->failed("dhdEnableForce");
    device->faulted = false;
  }
  reading->sequence = ++device->sequence;  // each call reads the device afresh
  return HAPTIC_DRIVER_OK;
}

// The setters return 0 or DHD_MOTOR_SATURATED (2) on success, -1 on error (§1.4).
int write_command(void* driver, const haptic_driver_command* command, double /*dt*/) {
  auto* device = static_cast<Device*>(driver);
  const DhdApi& api = device->api;
  const double* f = command->tau;
  int result;
  if (device->active_wrist || device->active_gripper) {
    const double* t = command->torque_W;
    result = api.SetForceAndTorqueAndGripperForce(f[0], f[1], f[2], device->active_wrist ? t[0] : 0.0,
                                                  device->active_wrist ? t[1] : 0.0,
                                                  device->active_wrist ? t[2] : 0.0,
                                                  device->active_gripper ? command->gripper_force : 0.0,
                                                  device->id);
    if (result < 0) return device->failed("dhdSetForceAndTorqueAndGripperForce");
  } else {
    result = api.SetForce(f[0], f[1], f[2], device->id);
    if (result < 0) return device->failed("dhdSetForce");
  }
  return HAPTIC_DRIVER_OK;
}

void enter_safe_state(void* driver) {
  auto* device = static_cast<Device*>(driver);
  device->api.SetForce(0.0, 0.0, 0.0, device->id);
  device->api.SetBrakes(kDhdOn, device->id);
}

void set_log(void* driver, haptic_driver_log_fn log, void* context) {
  auto* device = static_cast<Device*>(driver);
  device->log = log;
  device->log_context = context;
}

int list_devices(const char* params_json, char* list, size_t size) {
  std::string out;
  int found = -1;
  try {
    const haptic::vendor::DriverParams params = read_params(params_json);
    std::string why;
    void* library = load_runtime(params.text("library").value_or(""), why);
    if (library == nullptr) {
      out = why;
    } else {
      DhdApi api;
      if (const std::string missing = resolve(library, api); !missing.empty()) {
        out = "the Force Dimension runtime lacks " + missing;
      } else {
        const int count = api.GetDeviceCount();
        if (count < 0) {
          out = "dhdGetDeviceCount: " + vendor_error(api);
        } else {
          found = count;
          for (int index = 0; index < count; ++index) {
            const int id = api.OpenID(static_cast<char>(index));
            std::string description = "(in use or unreadable: " + vendor_error(api) + ")";
            if (id >= 0) {
              ushort serial = 0;
              api.GetSerialNumber(&serial, static_cast<char>(id));
              const char* name = api.GetSystemName(static_cast<char>(id));
              description = std::string("Force Dimension ") + (name != nullptr ? name : "device") +
                            ", serial " + std::to_string(serial);
              api.Close(static_cast<char>(id));
            }
            out += "{\"index\": " + std::to_string(index) + "}\t" + description + "\n";
          }
        }
      }
      dlclose(library);
    }
  } catch (const std::exception& failure) {
    out = failure.what();
  }
  std::snprintf(list, size, "%s", out.c_str());
  return found;
}

void last_error(void* driver, char* error) {
  const auto* device = static_cast<const Device*>(driver);
  const char* call = device->failed_call.load(std::memory_order_acquire);
  if (call == nullptr) {
    error[0] = '\0';
    return;
  }
  const int code = device->failed_code.load(std::memory_order_relaxed);
  if (code == 0) {  // a refusal of this driver's own, not the runtime's
    std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", call);
    return;
  }
  const char* text = device->api.ErrorGetStr(code);  // a fixed string of the runtime's
  std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s: %s (DHD error %d)", call,
                text != nullptr ? text : "error", code);
}

const haptic_driver_api kApi = {
    HAPTIC_DRIVER_ABI_VERSION,
    sizeof(haptic_driver_info),
    sizeof(haptic_driver_reading),
    sizeof(haptic_driver_command),
    create,
    destroy,
    describe,
    start,
    stop,
    read_sensors,
    write_command,
    enter_safe_state,
    nullptr,  // server-clocked: the SDK has no servo callback to hand the loop
    set_log,
    list_devices,
    last_error,
};

}  // namespace

extern "C" HAPTIC_DRIVER_EXPORT const haptic_driver_api* haptic_driver_entry(void) { return &kApi; }
