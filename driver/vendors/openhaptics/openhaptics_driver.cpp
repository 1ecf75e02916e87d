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

#include "common/driver_adapter.hpp"
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

// The HDAPI's functions as declared from §2.2-§2.3, one list: X(return type, name, parameters);
// the symbol is "hd" + name.
#define HD_REQUIRED(X)                                                        \
  X(HHD, InitDevice, (HDstring config_name))                                  \
  X(void, DisableDevice, (HHD handle))                                        \
  X(void, MakeCurrentDevice, (HHD handle))                                    \
  X(void, BeginFrame, (HHD handle))                                           \
  X(void, EndFrame, (HHD handle))                                             \
  X(HDErrorInfo, GetError, ())                                                \
  X(HDstring, GetErrorString, (HDerror code))                                 \
  X(void, Enable, (HDenum cap))                                               \
  X(void, Disable, (HDenum cap))                                              \
  X(void, GetIntegerv, (HDenum name, int* values))                            \
  X(void, GetDoublev, (HDenum name, double* values))                          \
  X(HDstring, GetString, (HDenum name))                                       \
  X(void, SetDoublev, (HDenum name, const double* values))                    \
  X(HDenum, CheckCalibration, ())                                             \
  X(void, UpdateCalibration, (HDenum style))                                  \
  X(void, StartScheduler, ())                                                 \
  X(void, StopScheduler, ())                                                  \
  X(void, SetSchedulerRate, (unsigned long rate))                             \
  X(HDSchedulerHandle, ScheduleAsynchronous,                                  \
    (HDSchedulerCallback callback, void* user_data, unsigned short priority)) \
  X(void, Unschedule, (HDSchedulerHandle handle))

struct HdApi {
  HD_REQUIRED(HAPTIC_RUNTIME_FUNCTION)
};

/// Where the runtime is looked for (§2.1) and what to install when it is not there.
haptic::vendor::RuntimeSearch runtime_search() {
  return {{"libHD.so", "libHD.so.3.4", "libHD.so.3.4.0", "libHD.so.3.0"},
          "OpenHaptics runtime",
          "install OpenHaptics (libHD.so in /usr/lib) and the device's driver (Touch: libPhantomIOLib42.so, "
          "GTDD_HOME)"};
}

std::string resolve(void* library, HdApi& api) {
  haptic::vendor::Symbols symbols(library);
#define NEED_HD(type, name, params) symbols.need(api.name, "hd" #name);
  HD_REQUIRED(NEED_HD)
#undef NEED_HD
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

/// The failure code the servo thread records when a runtime call threw (no HD error is 0xffff).
constexpr HDerror kRuntimeThrew = 0xffff;

/// One device through the runtime's scheduler: the driver's device (common/driver_adapter.hpp).
struct Device : haptic::vendor::VendorDevice {
  static constexpr const char* kParams[] = {"library",   "device",        "rate",
                                            "calibrate", "apparent_mass", "apparent_damping"};
  static constexpr bool kDeviceClocked = true;  // run_servo: hapticd's tick inside the callback

  HAPTIC_VENDOR_DEVICE(Device);
  int run_servo(haptic_driver_tick_fn tick, void* context);

  ~Device() {
    if (scheduled) {  // a stop that failed midway: the callback must not outlive the device
      haptic::vendor::quietly([this] { api.StopScheduler(); });
      haptic::vendor::quietly([this] { api.Unschedule(servo); });
    }
    if (handle != kInvalidHandle) haptic::vendor::quietly([this] { api.DisableDevice(handle); });
  }

  /// The safe state on (enter_safe_state, stop): zero force from the next frame, a new epoch.
  void hold_safe() {
    std::uint64_t word = safe_word.load(std::memory_order_relaxed);
    while (!safe_word.compare_exchange_weak(word, (((word >> 1) + 1) << 1) | 1u, std::memory_order_acq_rel)) {
    }
  }
  bool safe() const { return (safe_word.load(std::memory_order_acquire) & 1u) != 0; }

  haptic::vendor::LoadedLibrary library;  // declared first: closed after the destructor's hdDisableDevice
  HdApi api;
  HHD handle = kInvalidHandle;
  std::string config_name, model, serial;
  double max_force = 0.0;
  double workspace_min[3] = {0, 0, 0}, workspace_max[3] = {0, 0, 0};
  int input_dof = 3;
  double rate_hz = 1000.0;
  bool calibrate = true;
  double apparent_mass[3] = {0, 0, 0}, apparent_damping[3] = {0, 0, 0};

  HDSchedulerHandle servo = 0;
  bool scheduled = false;
  // The sample (seqlock) and the force to apply next, in W (N), as bit patterns.
  std::atomic<std::uint64_t> sample_version{0};
  Sample sample;
  std::atomic<std::uint64_t> force_bits[3] = {{0}, {0}, {0}};
  // Bit 0: the safe state holds (zero force until the next write); above it, how many times it
  // was entered, so that a write that began before the latest enter_safe_state (a late one, beside
  // hapticd's watchdog) does not end it.
  std::atomic<std::uint64_t> safe_word{0};
  std::atomic<bool> failed{false};     // the runtime reported an error on the servo thread
  std::atomic<HDerror> failed_code{kSuccess};
  // What a runtime call on the servo thread threw (failed_code kRuntimeThrew): last_error's text.
  mutable std::mutex servo_exception_mutex;
  char servo_exception[HAPTIC_DRIVER_ERROR_SIZE] = {};
  std::uint64_t ticks = 0;              // servo ticks (servo thread only)
  std::uint64_t last_read_tick = 0;     // read() only
  // Device-clocked: hapticd's tick, called inside the callback; and run_servo's end.
  std::atomic<haptic_driver_tick_fn> tick_fn{nullptr};
  void* tick_context = nullptr;
  std::mutex servo_mutex;
  std::condition_variable servo_done;
  bool servo_finished = false;
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

/// hapticd's tick, device-clocked (none server-clocked): true when run_servo is to end.
bool tick_hapticd(Device* device) {
  haptic_driver_tick_fn tick = device->tick_fn.load(std::memory_order_acquire);
  if (tick == nullptr) return false;
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return tick(device->tick_context, static_cast<int64_t>(now.tv_sec) * 1000000000LL + now.tv_nsec) != 0;
}

/// One servo frame: its state into the sample, hapticd's tick where device-clocked (`ticked` then),
/// the newest force out. True when run_servo is to end.
bool servo_frame(Device* device, bool& ticked) {
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
  ticked = true;
  const bool stop = tick_hapticd(device);
  double force_w[3] = {0, 0, 0};
  if (!device->safe() && !device->failed.load(std::memory_order_acquire)) {
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
  return stop;
}

/// The scheduler's callback, once per servo tick on its thread (§2.3). A runtime call that throws
/// fails the device (as a frame the runtime could not read does) rather than ending the process on
/// the vendor's thread; hapticd's tick still runs, so the loop sees the fault.
HDCallbackCode servo_tick(void* user_data) {
  auto* device = static_cast<Device*>(user_data);
  bool ticked = false;
  bool stop = false;
  try {
    stop = servo_frame(device, ticked);
  } catch (...) {
    {
      std::lock_guard lock(device->servo_exception_mutex);
      std::snprintf(device->servo_exception, sizeof device->servo_exception, "the servo loop: %s",
                    haptic::vendor::current_exception_text());
    }
    device->failed_code.store(kRuntimeThrew, std::memory_order_relaxed);
    device->failed.store(true, std::memory_order_release);
    if (!ticked) stop = tick_hapticd(device);
  }
  if (stop) {
    std::lock_guard lock(device->servo_mutex);
    device->tick_fn.store(nullptr, std::memory_order_release);
    device->servo_finished = true;
    device->servo_done.notify_all();
  }
  return kCallbackContinue;
}

std::unique_ptr<Device> Device::open(const haptic::vendor::DriverParams& params) {
  using haptic::vendor::Refusal;
  auto device = std::make_unique<Device>();
  {
    device->library = haptic::vendor::open_runtime(params.text("library").value_or(""), runtime_search(),
                                                   device->api, resolve);
    HdApi& api = device->api;
    device->config_name = params.text("device").value_or("");
    // HD_DEFAULT_DEVICE is a NULL string: the first device (§2.3).
    device->handle = api.InitDevice(device->config_name.empty() ? nullptr : device->config_name.c_str());
    const std::string init_errors = drain_errors(api);
    if (device->handle == kInvalidHandle || !init_errors.empty()) {
      throw Refusal("hdInitDevice(" + (device->config_name.empty() ? std::string("the first device")
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
      throw Refusal("reading the device's description: " +
                    (errors.empty() ? "HD_NOMINAL_MAX_FORCE is not > 0" : errors));
    }
  }
  return device;
}

void Device::describe(haptic_driver_info& info) const {
  std::snprintf(info.name, sizeof info.name, "3D Systems %s, serial %s", model.c_str(), serial.c_str());
  info.joints = 3;
  info.dof = 3;
  info.buttons = kButtonCount;
  // The runtime's smoothed velocity (§2.5); the gimbal's orientation on a 6-DOF input device.
  info.capabilities = HAPTIC_DRIVER_MEASURED_RATES;
  if (input_dof >= 6) info.capabilities |= HAPTIC_DRIVER_ORIENTATION;
  info.max_force = max_force;
  for (int i = 0; i < 3; ++i) {
    info.workspace_min[i] = std::min(workspace_min[i], workspace_max[i]);
    info.workspace_max[i] = std::max(workspace_min[i], workspace_max[i]);
    info.apparent_mass[i] = apparent_mass[i];
    info.apparent_damping[i] = apparent_damping[i];
  }
  info.servo_rate_hz = rate_hz;
}

/// Calibrates the current device if it needs it (§2.3: update with its style until OK).
std::string calibrate_if_needed(Device& device) {
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

int Device::start() {
  api.MakeCurrentDevice(handle);
  if (const std::string why = calibrate_if_needed(*this); !why.empty()) {
    say(HAPTIC_DRIVER_LOG_ERROR, why);
    return HAPTIC_DRIVER_FAILED;
  }
  for (auto& bits : force_bits) store_double(bits, 0.0);
  safe_word.store(0, std::memory_order_release);
  api.Enable(kForceOutput);
  api.SetSchedulerRate(static_cast<unsigned long>(rate_hz));
  servo = api.ScheduleAsynchronous(&servo_tick, this, kMaxPriority);
  scheduled = true;
  api.StartScheduler();
  if (const std::string errors = drain_errors(api); !errors.empty()) {
    say(HAPTIC_DRIVER_LOG_ERROR, "starting the servo loop: " + errors);
    return HAPTIC_DRIVER_FAILED;
  }
  say(HAPTIC_DRIVER_LOG_INFO,
      "servo loop running at " + std::to_string(std::lround(rate_hz)) + " Hz, forces on " + model);
  return HAPTIC_DRIVER_OK;
}

void Device::stop() {
  hold_safe();  // the next frames command zero
  {
    std::lock_guard lock(servo_mutex);  // a run_servo waiting: let it return
    tick_fn.store(nullptr, std::memory_order_release);
    servo_finished = true;
    servo_done.notify_all();
  }
  api.StopScheduler();
  if (scheduled) api.Unschedule(servo);
  scheduled = false;
  api.Disable(kForceOutput);
  drain_errors(api);
}

int Device::read(haptic_driver_reading& reading) {
  if (failed.load(std::memory_order_acquire)) return HAPTIC_DRIVER_FAILED;
  // Before the servo loop's first tick there is no sample: wait for it (only at the start), rather
  // than report the device where it is not. 50 ms at most, not two periods: a loaded host may not
  // run the runtime's new scheduler thread that soon (a CI run failed the kit at tick 0 so). The
  // wait sleeps in steps of 0.2 ms rather than spinning: on a busy host a spinning reader takes
  // the very CPU time the scheduler thread needs to make its first tick.
  if (sample_version.load(std::memory_order_acquire) == 0) {
    timespec start{};
    clock_gettime(CLOCK_MONOTONIC, &start);
    const double limit_s = std::max(2.0 / rate_hz, 0.050);
    for (;;) {
      if (sample_version.load(std::memory_order_acquire) != 0) break;
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
    const std::uint64_t before = sample_version.load(std::memory_order_acquire);
    if (before % 2 != 0) continue;
    copy = sample;
    std::atomic_thread_fence(std::memory_order_acquire);
    if (sample_version.load(std::memory_order_relaxed) == before) break;
  }
  for (int i = 0; i < 3; ++i) {
    reading.q[i] = copy.position_W[i];
    reading.q_dot[i] = copy.velocity_W[i];
    reading.angular_velocity_W[i] = copy.angular_velocity_W[i];
  }
  std::memcpy(reading.orientation_W, copy.orientation_W, sizeof copy.orientation_W);
  reading.buttons = copy.buttons;
  reading.sequence = copy.tick;  // a new sample each servo tick
  return HAPTIC_DRIVER_OK;
}

int Device::write(const haptic_driver_command& command, double /*dt*/) {
  // Taken first: an enter_safe_state from here on is newer than this command (driver.h).
  const std::uint64_t safe_at_entry = safe_word.load(std::memory_order_acquire);
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(command.tau[i])) return HAPTIC_DRIVER_FAILED;
  }
  for (int i = 0; i < 3; ++i) store_double(force_bits[i], command.tau[i]);
  // A command after the safe state is the loop driving the device again (driver.h): forces flow
  // from the next frame, unless the safe state was entered again since this write began.
  if ((safe_at_entry & 1u) != 0) {
    std::uint64_t expected = safe_at_entry;
    safe_word.compare_exchange_strong(expected, safe_at_entry & ~std::uint64_t{1}, std::memory_order_acq_rel);
  }
  return failed.load(std::memory_order_acquire) ? HAPTIC_DRIVER_FAILED : HAPTIC_DRIVER_OK;
}

void Device::enter_safe_state() { hold_safe(); }  // zero from the next frame

int Device::run_servo(haptic_driver_tick_fn tick, void* context) {
  std::unique_lock lock(servo_mutex);
  tick_context = context;
  servo_finished = false;
  tick_fn.store(tick, std::memory_order_release);
  servo_done.wait(lock, [this] { return servo_finished; });
  return HAPTIC_DRIVER_OK;
}

int Device::list_devices(const haptic::vendor::DriverParams& params, std::string& out) {
  HdApi api;
  const haptic::vendor::LoadedLibrary library =
      haptic::vendor::open_runtime(params.text("library").value_or(""), runtime_search(), api, resolve);
  // The HDAPI cannot enumerate: it opens devices by the names Touch_Setup gave them. Ask for the
  // one named (or the first).
  const std::string name = params.text("device").value_or("");
  const HHD handle = api.InitDevice(name.empty() ? nullptr : name.c_str());
  if (const std::string errors = drain_errors(api); handle == kInvalidHandle || !errors.empty()) {
    out = "hdInitDevice(" + (name.empty() ? std::string("the first device") : "\"" + name + "\"") +
          "): " + (errors.empty() ? std::string("no device") : errors);
    return -1;
  }
  api.MakeCurrentDevice(handle);
  const char* model = api.GetString(kDeviceModelType);
  const char* serial = api.GetString(kDeviceSerialNumber);
  out = (name.empty() ? std::string("{}") : "{\"device\": \"" + name + "\"}") + "\t3D Systems " +
        (model != nullptr ? model : "device") + ", serial " + (serial != nullptr ? serial : "?") +
        (name.empty() ? " (the first device; others by their Touch_Setup names)" : "") + "\n";
  api.DisableDevice(handle);
  return 1;
}

void Device::last_error(char* error) const {
  if (!failed.load(std::memory_order_acquire)) {
    error[0] = '\0';
    return;
  }
  const HDerror code = failed_code.load(std::memory_order_relaxed);
  if (code == kRuntimeThrew) {
    std::lock_guard lock(servo_exception_mutex);
    std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", servo_exception);
    return;
  }
  const char* words = api.GetErrorString(code);  // a fixed string of the runtime's
  std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "the servo loop: %s (HD error 0x%04x)",
                words != nullptr ? words : "error", code);
}

}  // namespace

HAPTIC_VENDOR_DRIVER(Device)
