// hapticd's driver for 3D Systems devices (Touch, Touch X, Phantom Premium) through the vendor's
// OpenHaptics HD runtime (libHD), loaded at start with dlopen: built against <haptic/driver.h>
// alone, it needs neither OpenHaptics nor the device's driver to build.
//
// Every declaration of the vendor's API below is written from the public facts collected, with
// their sources, in driver/vendors/SOURCES.md (section 2; "§2.x" below): the HDAPI's C
// signatures, enum values, units and frames (OpenHaptics 3.0 headers and reference manual).
//
// The runtime owns the servo loop (its scheduler thread, 1000 Hz by default, §2.3). This driver
// schedules one asynchronous callback at the highest priority that, each servo tick, inside
// hdBeginFrame/hdEndFrame, takes the device's state and applies the latest force:
//   - device-clocked ("clock": "DEVICE", the right choice on hardware): hapticd's tick runs
//     inside that callback (run_servo), between reading the state and applying the force, so a
//     force computed from a sample reaches the device in the same servo tick;
//   - server-clocked (the default): hapticd's loop reads the newest state and leaves its force
//     for the next servo tick (up to one servo period of extra delay).
//
// The device at its tool point in W, the frame every hapticd vendor driver uses: x towards the
// operator, y to the right, z up. The HD device frame is x right, y up, z towards the user (§2.5),
// so W = (z_hd, x_hd, y_hd), as CHAI3D maps it (§2.5). Units: the HDAPI's mm and mm/s become m
// and m/s; forces are N both sides (§2.5).
//
// params (all optional):
//   "library": the runtime to load; default libHD.so, libHD.so.3.4, libHD.so.3.4.0, libHD.so.3.0
//   "device": the configuration name given to hdInitDevice (Touch_Setup's name, e.g. "Default
//             Device"); default: the first device (HD_DEFAULT_DEVICE)
//   "rate": the scheduler's rate in Hz (default 1000; the device decides which it takes, §2.3)
//   "calibrate": true (default): a device that needs calibration is calibrated at start with the
//             style it reports (an inkwell device: put the stylus in its inkwell)
//   "apparent_mass", "apparent_damping": [x, y, z] (kg, N·s/m): the device at its tool, from
//             one's own identification (3D Systems publishes none; default unknown)
#include <haptic/driver.h>

#include <dlfcn.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/driver_params.hpp"
#include "common/vendor_runtime.hpp"

namespace {

// ---- The HDAPI, as declared from SOURCES.md §2.2-§2.4 (plain C ABI on x86-64 Linux, §2.2) ----
using HHD = unsigned int;
using HDenum = unsigned int;
using HDerror = unsigned int;
using HDboolean = unsigned char;
using HDstring = const char*;
using HDSchedulerHandle = unsigned long;
using HDCallbackCode = unsigned int;
using HDSchedulerCallback = HDCallbackCode (*)(void* user_data);
struct HDErrorInfo {  // §2.2: returned by value
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};

constexpr HHD kInvalidHandle = 0xFFFFFFFFu;         // HD_INVALID_HANDLE (§2.4)
constexpr HDerror kSuccess = 0x0000;                // HD_SUCCESS
constexpr HDCallbackCode kCallbackDone = 0;         // HD_CALLBACK_DONE (§2.3)
constexpr HDCallbackCode kCallbackContinue = 1;     // HD_CALLBACK_CONTINUE
constexpr unsigned short kMaxPriority = 65535;      // HD_MAX_SCHEDULER_PRIORITY (§2.3)
constexpr HDenum kCurrentButtons = 0x2000;          // HD_CURRENT_BUTTONS (§2.4)
constexpr HDenum kCurrentPosition = 0x2050;         // HD_CURRENT_POSITION, mm (§2.5)
constexpr HDenum kCurrentVelocity = 0x2051;         // HD_CURRENT_VELOCITY, mm/s
constexpr HDenum kCurrentTransform = 0x2052;        // HD_CURRENT_TRANSFORM, column-major, mm
constexpr HDenum kCurrentAngularVelocity = 0x2053;  // HD_CURRENT_ANGULAR_VELOCITY, rad/s
constexpr HDenum kDeviceModelType = 0x2501;         // HD_DEVICE_MODEL_TYPE (hdGetString)
constexpr HDenum kDeviceSerialNumber = 0x2504;      // HD_DEVICE_SERIAL_NUMBER (hdGetString)
constexpr HDenum kUsableWorkspace = 0x2551;         // HD_USABLE_WORKSPACE_DIMENSIONS, 6 doubles mm
constexpr HDenum kInputDof = 0x2553;                // HD_INPUT_DOF
constexpr HDenum kCalibrationStyle = 0x2555;        // HD_CALIBRATION_STYLE (a bit mask)
constexpr HDenum kNominalMaxForce = 0x2603;         // HD_NOMINAL_MAX_FORCE, N
constexpr HDenum kCurrentForce = 0x2700;            // HD_CURRENT_FORCE, N
constexpr HDenum kForceOutput = 0x4000;             // HD_FORCE_OUTPUT
constexpr HDenum kCalibrationOk = 0x5000;           // HD_CALIBRATION_OK
constexpr int kStyleEncoderReset = 1;               // HD_CALIBRATION_ENCODER_RESET
constexpr int kStyleAuto = 2;                       // HD_CALIBRATION_AUTO
constexpr int kStyleInkwell = 4;                    // HD_CALIBRATION_INKWELL
constexpr int kButtonCount = 2;                     // HD_DEVICE_BUTTON_1/_2 on a Touch's stylus

struct HdApi {
  HHD (*InitDevice)(HDstring config_name) = nullptr;
  void (*DisableDevice)(HHD handle) = nullptr;
  void (*MakeCurrentDevice)(HHD handle) = nullptr;
  void (*BeginFrame)(HHD handle) = nullptr;
  void (*EndFrame)(HHD handle) = nullptr;
  HDErrorInfo (*GetError)() = nullptr;
  HDstring (*GetErrorString)(HDerror code) = nullptr;
  void (*Enable)(HDenum cap) = nullptr;
  void (*Disable)(HDenum cap) = nullptr;
  void (*GetIntegerv)(HDenum name, int* values) = nullptr;
  void (*GetDoublev)(HDenum name, double* values) = nullptr;
  HDstring (*GetString)(HDenum name) = nullptr;
  void (*SetDoublev)(HDenum name, const double* values) = nullptr;
  HDenum (*CheckCalibration)() = nullptr;
  void (*UpdateCalibration)(HDenum style) = nullptr;
  void (*StartScheduler)() = nullptr;
  void (*StopScheduler)() = nullptr;
  void (*SetSchedulerRate)(unsigned long rate) = nullptr;
  HDSchedulerHandle (*ScheduleAsynchronous)(HDSchedulerCallback callback, void* user_data,
                                            unsigned short priority) = nullptr;
  void (*Unschedule)(HDSchedulerHandle handle) = nullptr;
};

void* load_runtime(const std::string& wanted, std::string& error) {
  return haptic::vendor::load_runtime(wanted, {"libHD.so", "libHD.so.3.4", "libHD.so.3.4.0", "libHD.so.3.0"},
                                      "OpenHaptics runtime",
                                      "install OpenHaptics (libHD.so in /usr/lib) and the device's driver "
                                      "(Touch: libPhantomIOLib42.so, GTDD_HOME)",
                                      error);
}

std::string resolve(void* library, HdApi& api) {
  haptic::vendor::Symbols symbols(library);
  auto need = [&symbols](auto& slot, const char* name) { symbols.need(slot, name); };
  need(api.InitDevice, "hdInitDevice");
  need(api.DisableDevice, "hdDisableDevice");
  need(api.MakeCurrentDevice, "hdMakeCurrentDevice");
  need(api.BeginFrame, "hdBeginFrame");
  need(api.EndFrame, "hdEndFrame");
  need(api.GetError, "hdGetError");
  need(api.GetErrorString, "hdGetErrorString");
  need(api.Enable, "hdEnable");
  need(api.Disable, "hdDisable");
  need(api.GetIntegerv, "hdGetIntegerv");
  need(api.GetDoublev, "hdGetDoublev");
  need(api.GetString, "hdGetString");
  need(api.SetDoublev, "hdSetDoublev");
  need(api.CheckCalibration, "hdCheckCalibration");
  need(api.UpdateCalibration, "hdUpdateCalibration");
  need(api.StartScheduler, "hdStartScheduler");
  need(api.StopScheduler, "hdStopScheduler");
  need(api.SetSchedulerRate, "hdSetSchedulerRate");
  need(api.ScheduleAsynchronous, "hdScheduleAsynchronous");
  need(api.Unschedule, "hdUnschedule");
  return symbols.missing();
}

/// The runtime's errors since the last call, the most recent first (§2.3: an error stack), as
/// text; empty when there were none.
std::string drain_errors(const HdApi& api) {
  std::string text;
  for (int guard = 0; guard < 16; ++guard) {
    const HDErrorInfo info = api.GetError();
    if (info.errorCode == kSuccess) break;
    const char* words = api.GetErrorString(info.errorCode);
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", info.errorCode);
    text += (text.empty() ? "" : "; ") + std::string(words != nullptr ? words : "error") + " (HD error " + code + ")";
  }
  return text;
}

/// Pops what remains of the error stack without allocating (on the servo thread); bounded.
void clear_errors(const HdApi& api) {
  for (int guard = 0; guard < 16 && api.GetError().errorCode != kSuccess; ++guard) {
  }
}

/// HD's device frame (x right, y up, z towards the user) to W (x towards the operator, y right,
/// z up): (x, y, z)_W = (z, x, y)_hd (§2.5).
void to_w(const double hd[3], double w[3], double scale) {
  w[0] = hd[2] * scale;
  w[1] = hd[0] * scale;
  w[2] = hd[1] * scale;
}
void to_hd(const double w[3], double hd[3]) {
  hd[0] = w[1];
  hd[1] = w[2];
  hd[2] = w[0];
}

/// The rotation part of a column-major 4x4 transform (§2.5: T[col * 4 + row]) taken into W, as a
/// unit quaternion (w, x, y, z). R_W = P R_hd Pᵀ with P the axis permutation of to_w.
void quaternion_in_w(const double t[16], double q[4]) {
  double r_hd[3][3];
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) r_hd[row][col] = t[col * 4 + row];
  }
  static constexpr int kFrom[3] = {2, 0, 1};  // W axis i is HD axis kFrom[i]
  double m[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[i][j] = r_hd[kFrom[i]][kFrom[j]];
  }
  haptic::vendor::quaternion_of(m, q);
}

/// One servo tick's sample, published by the scheduler's callback and read by read(): a seqlock
/// (odd while being written), so neither side waits on the other.
struct Sample {
  double position_W[3] = {0, 0, 0};  // m
  double velocity_W[3] = {0, 0, 0};  // m/s
  double orientation_W[4] = {1, 0, 0, 0};
  double angular_velocity_W[3] = {0, 0, 0};
  std::uint32_t buttons = 0;
  std::uint64_t tick = 0;
};

struct Device {
  void* library = nullptr;
  HdApi api;
  HHD handle = kInvalidHandle;
  std::string config_name, model, serial;
  double max_force = 0.0;
  double workspace_min[3] = {0, 0, 0}, workspace_max[3] = {0, 0, 0};
  int input_dof = 3;
  double rate_hz = 1000.0;
  bool calibrate = true;
  double apparent_mass[3] = {0, 0, 0}, apparent_damping[3] = {0, 0, 0};
  haptic_driver_log_fn log = nullptr;
  void* log_context = nullptr;

  HDSchedulerHandle servo = 0;
  bool scheduled = false;
  // The sample (seqlock) and the force to apply next, in W (N), as bit patterns.
  std::atomic<std::uint64_t> sample_version{0};
  Sample sample;
  std::atomic<std::uint64_t> force_bits[3] = {{0}, {0}, {0}};
  std::atomic<bool> safe{false};       // enter_safe_state: zero force until the next write
  std::atomic<bool> failed{false};     // the runtime reported an error on the servo thread
  std::atomic<HDerror> failed_code{kSuccess};
  std::uint64_t ticks = 0;              // servo ticks (servo thread only)
  std::uint64_t last_read_tick = 0;     // read() only
  // Device-clocked: hapticd's tick, called inside the callback; and run_servo's end.
  std::atomic<haptic_driver_tick_fn> tick_fn{nullptr};
  void* tick_context = nullptr;
  std::mutex servo_mutex;
  std::condition_variable servo_done;
  bool servo_finished = false;

  void say(int level, const std::string& message) const {
    if (log != nullptr) log(log_context, level, message.c_str());
  }
};

double load_double(const std::atomic<std::uint64_t>& bits) {
  const std::uint64_t raw = bits.load(std::memory_order_relaxed);
  double value;
  std::memcpy(&value, &raw, sizeof value);
  return value;
}
void store_double(std::atomic<std::uint64_t>& bits, double value) {
  std::uint64_t raw;
  std::memcpy(&raw, &value, sizeof raw);
  bits.store(raw, std::memory_order_relaxed);
}

/// The scheduler's callback, once per servo tick on its thread (§2.3): the frame's state into the
/// sample, hapticd's tick where device-clocked, the newest force out.
HDCallbackCode servo_tick(void* user_data) {
  auto* device = static_cast<Device*>(user_data);
  const HdApi& api = device->api;
  api.BeginFrame(device->handle);
  double position[3] = {0, 0, 0}, velocity[3] = {0, 0, 0}, angular[3] = {0, 0, 0};
  double transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  int buttons = 0;
  api.GetDoublev(kCurrentPosition, position);
  api.GetDoublev(kCurrentVelocity, velocity);
  api.GetDoublev(kCurrentTransform, transform);
  api.GetDoublev(kCurrentAngularVelocity, angular);
  api.GetIntegerv(kCurrentButtons, &buttons);
  // A frame the runtime could not read (an unplugged device: HD_COMM_ERROR) publishes nothing: read()
  // then fails until a frame reads again.
  const HDErrorInfo read_error = api.GetError();
  if (read_error.errorCode != kSuccess) {
    device->failed_code.store(read_error.errorCode, std::memory_order_relaxed);
    device->failed.store(true, std::memory_order_release);
    clear_errors(api);
  } else {
    device->sample_version.fetch_add(1, std::memory_order_acq_rel);  // odd: writing
    to_w(position, device->sample.position_W, 1e-3);
    to_w(velocity, device->sample.velocity_W, 1e-3);
    quaternion_in_w(transform, device->sample.orientation_W);
    to_w(angular, device->sample.angular_velocity_W, 1.0);
    device->sample.buttons = static_cast<std::uint32_t>(buttons) & ((1u << kButtonCount) - 1);
    device->sample.tick = ++device->ticks;
    device->sample_version.fetch_add(1, std::memory_order_release);  // even: done
    if (device->failed.load(std::memory_order_relaxed)) {
      // The device answers again (plugged back in): its force output is off until enabled.
      api.Enable(kForceOutput);
      device->failed.store(false, std::memory_order_release);
    }
  }
  // Device-clocked: hapticd's tick, between the state and the force (a failed frame too, so the
  // loop sees the fault).
  bool stop = false;
  if (haptic_driver_tick_fn tick = device->tick_fn.load(std::memory_order_acquire)) {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    stop = tick(device->tick_context, static_cast<int64_t>(now.tv_sec) * 1000000000LL + now.tv_nsec) != 0;
  }
  double force_w[3] = {0, 0, 0};
  if (!device->safe.load(std::memory_order_acquire) && !device->failed.load(std::memory_order_acquire)) {
    for (int i = 0; i < 3; ++i) force_w[i] = load_double(device->force_bits[i]);
  }
  double force_hd[3];
  to_hd(force_w, force_hd);
  api.SetDoublev(kCurrentForce, force_hd);
  api.EndFrame(device->handle);
  const HDErrorInfo write_error = api.GetError();
  if (write_error.errorCode != kSuccess) {
    device->failed_code.store(write_error.errorCode, std::memory_order_relaxed);
    device->failed.store(true, std::memory_order_release);
    clear_errors(api);
  }
  if (stop) {
    std::lock_guard lock(device->servo_mutex);
    device->tick_fn.store(nullptr, std::memory_order_release);
    device->servo_finished = true;
    device->servo_done.notify_all();
  }
  return kCallbackContinue;
}

/// The params this driver takes (header comment), refusing any other.
haptic::vendor::DriverParams read_params(const char* params_json) {
  return haptic::vendor::DriverParams(
      params_json, {"library", "device", "rate", "calibrate", "apparent_mass", "apparent_damping"});
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
      return refuse("the OpenHaptics runtime lacks " + missing);
    }
    HdApi& api = device->api;
    device->config_name = params.text("device").value_or("");
    // HD_DEFAULT_DEVICE is a NULL string: the first device (§2.3).
    device->handle = api.InitDevice(device->config_name.empty() ? nullptr : device->config_name.c_str());
    const std::string init_errors = drain_errors(api);
    if (device->handle == kInvalidHandle || !init_errors.empty()) {
      dlclose(device->library);
      return refuse("hdInitDevice(" + (device->config_name.empty() ? std::string("the first device")
                                                                   : "\"" + device->config_name + "\"") +
                    "): " + (init_errors.empty() ? "no device" : init_errors) +
                    ": is it connected and set up (Touch_Setup), and may this user open it?");
    }
    api.MakeCurrentDevice(device->handle);
    const char* model = api.GetString(kDeviceModelType);
    const char* serial = api.GetString(kDeviceSerialNumber);
    device->model = model != nullptr ? model : "3D Systems device";
    device->serial = serial != nullptr ? serial : "?";
    double workspace_mm[6] = {0, 0, 0, 0, 0, 0};
    api.GetDoublev(kUsableWorkspace, workspace_mm);  // minX, minY, minZ, maxX, maxY, maxZ (§2.5)
    // The box in W: W's x is HD's z, y is x, z is y.
    const double lo_hd[3] = {workspace_mm[0], workspace_mm[1], workspace_mm[2]};
    const double hi_hd[3] = {workspace_mm[3], workspace_mm[4], workspace_mm[5]};
    to_w(lo_hd, device->workspace_min, 1e-3);
    to_w(hi_hd, device->workspace_max, 1e-3);
    api.GetDoublev(kNominalMaxForce, &device->max_force);
    api.GetIntegerv(kInputDof, &device->input_dof);
    device->rate_hz = params.number("rate").value_or(1000.0);
    device->calibrate = params.boolean("calibrate").value_or(true);
    if (auto m = params.triple("apparent_mass")) std::copy(m->begin(), m->end(), device->apparent_mass);
    if (auto b = params.triple("apparent_damping")) std::copy(b->begin(), b->end(), device->apparent_damping);
    if (const std::string errors = drain_errors(api); !errors.empty() || !(device->max_force > 0.0)) {
      api.DisableDevice(device->handle);
      dlclose(device->library);
      return refuse("reading the device's description: " +
                    (errors.empty() ? "HD_NOMINAL_MAX_FORCE is not > 0" : errors));
    }
    return device.release();
  } catch (const std::exception& failure) {
    return refuse(failure.what());
  }
}

void destroy(void* driver) {
  auto* device = static_cast<Device*>(driver);
  device->api.DisableDevice(device->handle);
  dlclose(device->library);
  delete device;
}

int describe(void* driver, haptic_driver_info* info) {
  const auto* device = static_cast<const Device*>(driver);
  std::memset(info, 0, sizeof *info);
  std::snprintf(info->name, sizeof info->name, "3D Systems %s, serial %s", device->model.c_str(),
                device->serial.c_str());
  info->joints = 3;
  info->dof = 3;
  info->buttons = kButtonCount;
  // The runtime's smoothed velocity (§2.5); the gimbal's orientation on a 6-DOF input device.
  info->capabilities = HAPTIC_DRIVER_MEASURED_RATES;
  if (device->input_dof >= 6) info->capabilities |= HAPTIC_DRIVER_ORIENTATION;
  info->max_force = device->max_force;
  for (int i = 0; i < 3; ++i) {
    info->workspace_min[i] = std::min(device->workspace_min[i], device->workspace_max[i]);
    info->workspace_max[i] = std::max(device->workspace_min[i], device->workspace_max[i]);
    info->apparent_mass[i] = device->apparent_mass[i];
    info->apparent_damping[i] = device->apparent_damping[i];
  }
  info->servo_rate_hz = device->rate_hz;
  return HAPTIC_DRIVER_OK;
}

/// Calibrates the current device if it needs it (§2.3: update with its style until OK).
std::string calibrate(Device& device) {
  const HdApi& api = device.api;
  if (api.CheckCalibration() == kCalibrationOk) return {};
  if (!device.calibrate) return "the device needs calibration and params.calibrate is false";
  int styles = 0;
  api.GetIntegerv(kCalibrationStyle, &styles);
  const int style = (styles & kStyleEncoderReset) != 0 ? kStyleEncoderReset
                    : (styles & kStyleAuto) != 0       ? kStyleAuto
                                                       : kStyleInkwell;
  device.say(HAPTIC_DRIVER_LOG_WARNING, style == kStyleInkwell
                                            ? "calibrating: put the stylus in its inkwell"
                                            : "calibrating the device's encoders");
  for (int attempt = 0; attempt < 5000 && api.CheckCalibration() != kCalibrationOk; ++attempt) {
    api.UpdateCalibration(static_cast<HDenum>(style));
    if (const std::string errors = drain_errors(api); !errors.empty()) return "calibration: " + errors;
    if (api.CheckCalibration() == kCalibrationOk) break;
    timespec pause{0, 1000000};  // the inkwell: wait for the stylus, 5 s at most
    nanosleep(&pause, nullptr);
  }
  if (api.CheckCalibration() != kCalibrationOk) return "calibration did not complete within 5 s";
  device.say(HAPTIC_DRIVER_LOG_INFO, "calibrated");
  return {};
}

int start(void* driver) {
  auto* device = static_cast<Device*>(driver);
  HdApi& api = device->api;
  api.MakeCurrentDevice(device->handle);
  if (const std::string why = calibrate(*device); !why.empty()) {
    device->say(HAPTIC_DRIVER_LOG_ERROR, why);
    return HAPTIC_DRIVER_FAILED;
  }
  for (auto& bits : device->force_bits) store_double(bits, 0.0);
  device->safe.store(false);
  api.Enable(kForceOutput);
  api.SetSchedulerRate(static_cast<unsigned long>(device->rate_hz));
  device->servo = api.ScheduleAsynchronous(&servo_tick, device, kMaxPriority);
  device->scheduled = true;
  api.StartScheduler();
  if (const std::string errors = drain_errors(api); !errors.empty()) {
    device->say(HAPTIC_DRIVER_LOG_ERROR, "starting the servo loop: " + errors);
    return HAPTIC_DRIVER_FAILED;
  }
  device->say(HAPTIC_DRIVER_LOG_INFO, "servo loop running at " + std::to_string(std::lround(device->rate_hz)) +
                                          " Hz, forces on " + device->model);
  return HAPTIC_DRIVER_OK;
}

void stop(void* driver) {
  auto* device = static_cast<Device*>(driver);
  HdApi& api = device->api;
  device->safe.store(true, std::memory_order_release);  // the next frames command zero
  {
    std::lock_guard lock(device->servo_mutex);  // a run_servo waiting: let it return
    device->tick_fn.store(nullptr, std::memory_order_release);
    device->servo_finished = true;
    device->servo_done.notify_all();
  }
  api.StopScheduler();
  if (device->scheduled) api.Unschedule(device->servo);
  device->scheduled = false;
  api.Disable(kForceOutput);
  drain_errors(api);
}

int read_sensors(void* driver, haptic_driver_reading* reading) {
  auto* device = static_cast<Device*>(driver);
  if (device->failed.load(std::memory_order_acquire)) return HAPTIC_DRIVER_FAILED;
  // Before the servo loop's first tick there is no sample: wait for it (only at the start), rather
  // than report the device where it is not. 50 ms at most, not two periods: a loaded host may not
  // run the runtime's new scheduler thread that soon (a CI run failed the kit at tick 0 so). The
  // wait sleeps in steps of 0.2 ms rather than spinning: on a busy host a spinning reader takes
  // the very CPU time the scheduler thread needs to make its first tick.
  if (device->sample_version.load(std::memory_order_acquire) == 0) {
    timespec start{};
    clock_gettime(CLOCK_MONOTONIC, &start);
    const double limit_s = std::max(2.0 / device->rate_hz, 0.050);
    for (;;) {
      if (device->sample_version.load(std::memory_order_acquire) != 0) break;
      timespec now{};
      clock_gettime(CLOCK_MONOTONIC, &now);
      if ((now.tv_sec - start.tv_sec) + 1e-9 * (now.tv_nsec - start.tv_nsec) > limit_s) {
        return HAPTIC_DRIVER_FAILED;
      }
      timespec pause{0, 200'000};
      nanosleep(&pause, nullptr);
    }
  }
  Sample copy;
  for (;;) {  // the seqlock: retry while the servo thread writes
    const std::uint64_t before = device->sample_version.load(std::memory_order_acquire);
    if (before % 2 != 0) continue;
    copy = device->sample;
    std::atomic_thread_fence(std::memory_order_acquire);
    if (device->sample_version.load(std::memory_order_relaxed) == before) break;
  }
  for (int i = 0; i < 3; ++i) {
    reading->q[i] = copy.position_W[i];
    reading->q_dot[i] = copy.velocity_W[i];
    reading->angular_velocity_W[i] = copy.angular_velocity_W[i];
  }
  std::memcpy(reading->orientation_W, copy.orientation_W, sizeof copy.orientation_W);
  reading->buttons = copy.buttons;
  reading->sequence = copy.tick;  // a new sample each servo tick
  return HAPTIC_DRIVER_OK;
}

int write_command(void* driver, const haptic_driver_command* command, double /*dt*/) {
  auto* device = static_cast<Device*>(driver);
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(command->tau[i])) return HAPTIC_DRIVER_FAILED;
  }
  for (int i = 0; i < 3; ++i) store_double(device->force_bits[i], command->tau[i]);
  // A command after the safe state is the loop driving the device again (it writes only after a
  // good reading, and a zero command right after entering the safe state): forces flow again, as
  // the Force Dimension driver's next dhdSetForce does, without a restart.
  device->safe.store(false, std::memory_order_release);
  return device->failed.load(std::memory_order_acquire) ? HAPTIC_DRIVER_FAILED : HAPTIC_DRIVER_OK;
}

void enter_safe_state(void* driver) {
  static_cast<Device*>(driver)->safe.store(true, std::memory_order_release);  // zero from the next frame
}

int run_servo(void* driver, haptic_driver_tick_fn tick, void* context) {
  auto* device = static_cast<Device*>(driver);
  std::unique_lock lock(device->servo_mutex);
  device->tick_context = context;
  device->servo_finished = false;
  device->tick_fn.store(tick, std::memory_order_release);
  device->servo_done.wait(lock, [device] { return device->servo_finished; });
  return HAPTIC_DRIVER_OK;
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
      HdApi api;
      if (const std::string missing = resolve(library, api); !missing.empty()) {
        out = "the OpenHaptics runtime lacks " + missing;
      } else {
        // The HDAPI cannot enumerate: it opens devices by the names Touch_Setup gave them. Ask
        // for the one named (or the first).
        const std::string name = params.text("device").value_or("");
        const HHD handle = api.InitDevice(name.empty() ? nullptr : name.c_str());
        const std::string errors = drain_errors(api);
        if (handle == kInvalidHandle || !errors.empty()) {
          out = "hdInitDevice(" + (name.empty() ? std::string("the first device") : "\"" + name + "\"") +
                "): " + (errors.empty() ? std::string("no device") : errors);
        } else {
          api.MakeCurrentDevice(handle);
          const char* model = api.GetString(kDeviceModelType);
          const char* serial = api.GetString(kDeviceSerialNumber);
          out = (name.empty() ? std::string("{}") : "{\"device\": \"" + name + "\"}") + "\t3D Systems " +
                (model != nullptr ? model : "device") + ", serial " + (serial != nullptr ? serial : "?") +
                (name.empty() ? " (the first device; others by their Touch_Setup names)" : "") + "\n";
          api.DisableDevice(handle);
          found = 1;
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
  if (!device->failed.load(std::memory_order_acquire)) {
    error[0] = '\0';
    return;
  }
  const HDerror code = device->failed_code.load(std::memory_order_relaxed);
  const char* words = device->api.GetErrorString(code);  // a fixed string of the runtime's
  std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "the servo loop: %s (HD error 0x%04x)",
                words != nullptr ? words : "error", code);
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
    run_servo,
    set_log,
    list_devices,
    last_error,
};

}  // namespace

extern "C" HAPTIC_DRIVER_EXPORT const haptic_driver_api* haptic_driver_entry(void) { return &kApi; }
