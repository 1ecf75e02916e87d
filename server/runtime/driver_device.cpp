#include "runtime/driver_device.hpp"

#include <dlfcn.h>
#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <climits>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "runtime/realtime.hpp"

namespace haptic::runtime {
namespace {

// The hop to the driver thread and back, asleep both ways, costs ~12 µs per call on a 2-core VM
// (~25 µs a tick); spinning briefly where the other side answers soon cuts that (device_bench,
// BM_Device_DriverPointMass). The loop spins for a reply this long before it sleeps:
constexpr std::int64_t kSpinForReplyNs = 100'000;
// and the driver thread, after a call, for the next request (the tick's write after its read):
constexpr std::int64_t kSpinAfterCallNs = 100'000;

/// Blocks while `word` holds `expected`, for at most timeout_ns (< 0: no limit).
void futex_wait(std::atomic<std::uint32_t>& word, std::uint32_t expected, std::int64_t timeout_ns) {
  timespec timeout{};
  timespec* limit = nullptr;
  if (timeout_ns >= 0) {
    timeout.tv_sec = static_cast<time_t>(timeout_ns / 1'000'000'000);
    timeout.tv_nsec = static_cast<long>(timeout_ns % 1'000'000'000);
    limit = &timeout;
  }
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, expected, limit,
          nullptr, 0);
}

void futex_wake(std::atomic<std::uint32_t>& word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr,
          nullptr, 0);
}

bool finite_box(const double lo[3], const double hi[3]) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(lo[i]) || !std::isfinite(hi[i]) || lo[i] > hi[i]) return false;
  }
  return true;
}

bool finite_non_negative(const double values[], int n) {
  for (int i = 0; i < n; ++i) {
    if (!(std::isfinite(values[i]) && values[i] >= 0.0)) return false;
  }
  return true;
}

/// Empty when ABI 2's fields are usable (a version 1 driver's are all 0), else what is wrong.
std::string check_info_v2(const haptic_driver_info& info) {
  if (!finite_non_negative(info.apparent_mass, 3) || !finite_non_negative(info.apparent_damping, 3)) {
    return "apparent_mass and apparent_damping must be finite and >= 0 on every axis (0: unknown)";
  }
  if (!finite_non_negative(info.apparent_inertia, 3) ||
      !finite_non_negative(info.apparent_rotational_damping, 3)) {
    return "apparent_inertia and apparent_rotational_damping must be finite and >= 0 on every axis";
  }
  if ((info.capabilities & HAPTIC_DRIVER_TORQUE_OUTPUT) != 0 &&
      !(std::isfinite(info.max_torque) && info.max_torque > 0.0)) {
    return "TORQUE_OUTPUT: max_torque must be finite and > 0 N*m, got " + std::to_string(info.max_torque);
  }
  if ((info.capabilities & HAPTIC_DRIVER_GRIPPER) != 0) {
    if (!(std::isfinite(info.gripper_max_force) && info.gripper_max_force > 0.0)) {
      return "GRIPPER: gripper_max_force must be finite and > 0 N, got " +
             std::to_string(info.gripper_max_force);
    }
    if (!(std::isfinite(info.gripper_min) && std::isfinite(info.gripper_max) &&
          info.gripper_min <= info.gripper_max)) {
      return "GRIPPER: gripper_min/gripper_max must be finite with min <= max";
    }
  }
  return {};
}

/// Empty when the description is usable, else what is wrong with it.
std::string check_info(const haptic_driver_info& info, bool device_clocked, bool has_run_servo) {
  if (info.joints < 1 || info.joints > HAPTIC_DRIVER_MAX_JOINTS) {
    return "joints must be 1 ... " + std::to_string(HAPTIC_DRIVER_MAX_JOINTS) + ", got " +
           std::to_string(info.joints);
  }
  if (info.dof < 1 || info.dof > 3) return "dof must be 1 ... 3, got " + std::to_string(info.dof);
  if (info.buttons > 32) return "buttons must be 0 ... 32, got " + std::to_string(info.buttons);
  if (!(std::isfinite(info.max_force) && info.max_force > 0.0)) {
    return "max_force must be finite and > 0 N, got " + std::to_string(info.max_force);
  }
  if (!finite_box(info.workspace_min, info.workspace_max)) {
    return "workspace_min/workspace_max must be finite with min <= max on every axis";
  }
  if (device_clocked) {
    if (!has_run_servo) return "device-clocked (clock DEVICE) but the driver has no run_servo";
    if (!(std::isfinite(info.servo_rate_hz) && info.servo_rate_hz >= 100.0 &&
          info.servo_rate_hz <= 10000.0)) {
      return "device-clocked: servo_rate_hz must be 100 ... 10000 Hz, got " +
             std::to_string(info.servo_rate_hz);
    }
  }
  return check_info_v2(info);
}

}  // namespace

DriverStructSizes driver_struct_sizes(std::uint32_t abi_version) {
  switch (abi_version) {
    case 1:  // version 2 appended to each struct: version 1's ends where version 2's fields begin
      return {offsetof(haptic_driver_info, apparent_mass), offsetof(haptic_driver_reading, angular_velocity_W),
              offsetof(haptic_driver_command, torque_W)};
    case 2:
      return {sizeof(haptic_driver_info), sizeof(haptic_driver_reading), sizeof(haptic_driver_command)};
    default:
      return {};
  }
}

std::vector<std::string> driver_folders(const std::vector<std::string>& extra) {
  std::vector<std::string> candidates = extra;
  std::error_code error;
  const std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    candidates.push_back((binary.parent_path().parent_path() / HAPTIC_INSTALL_LIBDIR / "hapticd").string());
    // A hapticd run from its build tree also finds the drivers built beside it.
    if (binary.string().rfind(std::string(HAPTIC_BUILD_TREE) + "/", 0) == 0) {
      candidates.push_back(std::string(HAPTIC_BUILD_TREE) + "/driver");
    }
  }
  std::vector<std::string> folders;
  for (const std::string& folder : candidates) {
    std::error_code missing;
    if (!std::filesystem::is_directory(folder, missing)) continue;
    const std::string canonical = std::filesystem::weakly_canonical(folder, missing).string();
    if (std::find(folders.begin(), folders.end(), canonical) == folders.end()) folders.push_back(canonical);
  }
  return folders;
}

std::string resolve_driver_library(const std::string& library) {
  if (library.find('/') != std::string::npos) return library;
  for (const std::string& folder : driver_folders()) {
    const std::filesystem::path candidate = std::filesystem::path(folder) / library;
    std::error_code error;
    if (std::filesystem::is_regular_file(candidate, error)) return candidate.string();
  }
  return library;
}

DriverListing list_driver_devices(const std::string& library, const std::string& params_json) {
  DriverListing listing;
  void* handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* reason = dlerror();
    listing.error = std::string("cannot load: ") + (reason != nullptr ? reason : "unknown");
    return listing;
  }
  auto entry = reinterpret_cast<haptic_driver_entry_fn>(dlsym(handle, HAPTIC_DRIVER_ENTRY_SYMBOL));
  const haptic_driver_api* api = entry != nullptr ? entry() : nullptr;
  listing.is_driver = entry != nullptr;
  if (api == nullptr) {
    listing.error = "exports no " HAPTIC_DRIVER_ENTRY_SYMBOL "(); is it a hapticd driver?";
  } else if (api->abi_version < HAPTIC_DRIVER_ABI_VERSION_MIN || api->abi_version > HAPTIC_DRIVER_ABI_VERSION) {
    listing.error = "built for driver ABI version " + std::to_string(api->abi_version) +
                    ", this hapticd speaks versions " + std::to_string(HAPTIC_DRIVER_ABI_VERSION_MIN) +
                    " to " + std::to_string(HAPTIC_DRIVER_ABI_VERSION);
  } else {
    listing.abi_version = api->abi_version;
    listing.can_list = api->abi_version >= 2 && api->list_devices != nullptr;
  }
  if (listing.can_list) {
    std::string text(16384, '\0');
    const int found = api->list_devices(params_json.c_str(), text.data(), text.size());
    text.back() = '\0';
    text.resize(std::strlen(text.c_str()));
    if (found < 0) {
      listing.error = text.empty() ? "list_devices() failed without a reason" : text;
    } else {
      std::size_t start = 0;
      while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        const std::string line = text.substr(start, end - start);
        start = end + 1;
        if (line.empty()) continue;
        const std::size_t tab = line.find('\t');
        listing.devices.push_back(tab == std::string::npos
                                      ? DriverListing::Entry{"{}", line}
                                      : DriverListing::Entry{line.substr(0, tab), line.substr(tab + 1)});
      }
    }
  }
  dlclose(handle);
  return listing;
}

void DriverDevice::CallState::log_trampoline(void* self, int level, const char* message) {
  const auto* state = static_cast<const CallState*>(self);
  if (state->log && message != nullptr) state->log(level, message);
}

DriverDevice::DriverDevice(const DriverOptions& options) : options_(options) {
  const std::string where = "driver \"" + options.library + "\": ";
  const std::string path = resolve_driver_library(options.library);
  library_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library_ == nullptr) {
    const char* reason = dlerror();
    throw std::runtime_error(where + "cannot load: " + (reason != nullptr ? reason : "unknown"));
  }
  auto entry = reinterpret_cast<haptic_driver_entry_fn>(dlsym(library_, HAPTIC_DRIVER_ENTRY_SYMBOL));
  if (entry == nullptr) {
    dlclose(library_);
    throw std::runtime_error(where + "exports no " HAPTIC_DRIVER_ENTRY_SYMBOL "(); is it a hapticd driver?");
  }
  api_ = entry();
  std::string refused;
  if (api_ == nullptr) {
    refused = HAPTIC_DRIVER_ENTRY_SYMBOL "() returned NULL";
  } else if (api_->abi_version < HAPTIC_DRIVER_ABI_VERSION_MIN ||
             api_->abi_version > HAPTIC_DRIVER_ABI_VERSION) {
    refused = "built for driver ABI version " + std::to_string(api_->abi_version) +
              ", this hapticd speaks versions " + std::to_string(HAPTIC_DRIVER_ABI_VERSION_MIN) + " to " +
              std::to_string(HAPTIC_DRIVER_ABI_VERSION) +
              "; rebuild the driver against this hapticd's haptic/driver.h";
  } else if (const DriverStructSizes sizes = driver_struct_sizes(api_->abi_version);
             api_->info_size != sizes.info || api_->reading_size != sizes.reading ||
             api_->command_size != sizes.command) {
    refused = "its structs' sizes differ from this hapticd's haptic/driver.h for ABI version " +
              std::to_string(api_->abi_version) + " (info " + std::to_string(api_->info_size) + "/" +
              std::to_string(sizes.info) + ", reading " + std::to_string(api_->reading_size) + "/" +
              std::to_string(sizes.reading) + ", command " + std::to_string(api_->command_size) + "/" +
              std::to_string(sizes.command) + " bytes); rebuild the driver against it";
  } else if (api_->create == nullptr || api_->destroy == nullptr || api_->describe == nullptr ||
             api_->start == nullptr || api_->stop == nullptr || api_->read == nullptr ||
             api_->write == nullptr || api_->enter_safe_state == nullptr) {
    refused = "its function table leaves a required function NULL (all but run_servo are required)";
  }
  if (refused.empty()) {
    char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
    driver_ = api_->create(options.params_json.c_str(), error);
    error[HAPTIC_DRIVER_ERROR_SIZE - 1] = '\0';
    if (driver_ == nullptr) refused = std::string("create() refused: ") + (error[0] ? error : "no reason given");
  }
  if (refused.empty()) {
    if (api_->describe(driver_, &info_) != HAPTIC_DRIVER_OK) {
      refused = "describe() failed";
    } else {
      info_.name[sizeof(info_.name) - 1] = '\0';
      if (auto e = check_info(info_, options.device_clocked, api_->run_servo != nullptr); !e.empty()) {
        refused = "describe(): " + e;
      }
    }
    if (!refused.empty()) api_->destroy(driver_);
  }
  if (!refused.empty()) {
    dlclose(library_);
    throw std::runtime_error(where + refused);
  }
  calls_->log = options.log;
  if (api_->abi_version >= 2 && api_->set_log != nullptr) {
    api_->set_log(driver_, &CallState::log_trampoline, calls_.get());
  }
  calls_->api = api_;
  calls_->driver = driver_;
  description_.name = info_.name;
  description_.model = "driver";
  description_.dof = info_.dof;
  description_.joints = info_.joints;
  description_.buttons = info_.buttons;
  description_.max_force = info_.max_force;
  description_.workspace_min = {info_.workspace_min[0], info_.workspace_min[1], info_.workspace_min[2]};
  description_.workspace_max = {info_.workspace_max[0], info_.workspace_max[1], info_.workspace_max[2]};
  DeviceCapabilities& c = description_.capabilities;
  c.measured_rates = (info_.capabilities & HAPTIC_DRIVER_MEASURED_RATES) != 0;
  c.force_sensor = (info_.capabilities & (HAPTIC_DRIVER_FORCE_SENSOR | HAPTIC_DRIVER_TORQUE_SENSORS)) != 0;
  c.brakes = (info_.capabilities & HAPTIC_DRIVER_BRAKES) != 0;
  c.gravity = (info_.capabilities & HAPTIC_DRIVER_GRAVITY) != 0;
  c.orientation = (info_.capabilities & HAPTIC_DRIVER_ORIENTATION) != 0;
  // Torque and the angular velocity exist from ABI 2 on; a version 1 driver's structs end before.
  c.torque = api_->abi_version >= 2 && c.orientation && (info_.capabilities & HAPTIC_DRIVER_TORQUE_OUTPUT) != 0;
  if (c.torque) {
    description_.max_torque = info_.max_torque;
    const double* inertia = info_.apparent_inertia;
    const double* rotational_damping = info_.apparent_rotational_damping;
    if (inertia[0] > 0.0 && inertia[1] > 0.0 && inertia[2] > 0.0) {
      description_.apparent_inertia = std::min({inertia[0], inertia[1], inertia[2]});
      description_.apparent_rotational_damping =
          std::min({rotational_damping[0], rotational_damping[1], rotational_damping[2]});
    }
  }
  description_.simulated = false;
  // The port's mass-damper for the stability report and passivity: the weakest axis (the least
  // mass and the least damping), and only when the driver knows all three axes' masses.
  const double* mass = info_.apparent_mass;
  const double* damping = info_.apparent_damping;
  if (mass[0] > 0.0 && mass[1] > 0.0 && mass[2] > 0.0) {
    description_.apparent_mass = std::min({mass[0], mass[1], mass[2]});
    description_.apparent_damping = std::min({damping[0], damping[1], damping[2]});
  }
  // Figures measured on the bench take the place of the driver's (docs/identification.md).
  if (options_.profile) {
    const auto& p = *options_.profile;
    description_.apparent_mass = std::min({p.apparent_mass[0], p.apparent_mass[1], p.apparent_mass[2]});
    description_.apparent_damping = std::min({p.apparent_damping[0], p.apparent_damping[1], p.apparent_damping[2]});
    description_.delay_s = p.delay_s;
    description_.actuator_lag_s = p.actuator_lag_s;
  }
}

DriverDevice::~DriverDevice() {
  stop();
  if (thread_.joinable()) {
    // A call that never came back: its code may still run, so the thread keeps its state and
    // the library stays loaded.
    thread_.detach();
    static_cast<void>(calls_.release());
    return;
  }
  api_->destroy(driver_);
  dlclose(library_);
}

DeviceStatus DriverDevice::start() {
  if (api_->start(driver_) != HAPTIC_DRIVER_OK) return DeviceStatus::kError;
  started_ = true;
  if (!options_.device_clocked && options_.call_timeout_s > 0.0 && !thread_.joinable()) {
    calls_->request.store(kNone, std::memory_order_relaxed);
    thread_ = std::thread([state = calls_.get(), priority = options_.thread_priority] { state->serve(priority); });
  }
  return DeviceStatus::kOk;
}

void DriverDevice::stop() {
  if (!started_) return;
  started_ = false;
  api_->stop(driver_);  // also what releases a call that hangs, in a driver that can
  if (!thread_.joinable()) return;
  CallState& calls = *calls_;
  if (hung()) {
    // Give the late call a moment to come back now that the driver was told to stop.
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (calls.request.load(std::memory_order_acquire) != kNone &&
           std::chrono::steady_clock::now() < give_up) {
      futex_wait(calls.done, calls.done.load(std::memory_order_acquire), 10'000'000);
    }
    if (calls.request.load(std::memory_order_acquire) != kNone) return;  // still inside the driver
  }
  calls.request.store(kQuit, std::memory_order_release);
  futex_wake(calls.request);
  thread_.join();
}

void DriverDevice::CallState::serve(int priority) {
  if (priority > 0) apply_realtime(priority);  // as the loop, where permitted: the loop waits on this thread
  std::int64_t spin_until = 0;  // after a call, the next (a tick's write follows its read) comes soon
  for (;;) {
    const std::uint32_t what = request.load(std::memory_order_acquire);
    if (what == kNone) {
      if (monotonic_now_ns() < spin_until) continue;
      futex_wait(request, kNone, -1);
      continue;
    }
    if (what == kQuit) return;
    result = call_driver(static_cast<Call>(what));
    request.store(kNone, std::memory_order_relaxed);
    done.fetch_add(1, std::memory_order_release);
    futex_wake(done);
    spin_until = monotonic_now_ns() + kSpinAfterCallNs;
  }
}

int DriverDevice::CallState::call_driver(Call what) {
  return what == kRead ? api->read(driver, &reading) : api->write(driver, &command, dt);
}

bool DriverDevice::call(Call what, int& result) {
  CallState& calls = *calls_;
  if (!thread_.joinable()) {
    result = calls.call_driver(what);
    return true;
  }
  const std::uint32_t seen = calls.done.load(std::memory_order_acquire);
  calls.request.store(what, std::memory_order_release);
  futex_wake(calls.request);
  const std::int64_t deadline =
      monotonic_now_ns() + static_cast<std::int64_t>(std::llround(options_.call_timeout_s * 1e9));
  // A driver call is usually short: wait for it spinning first, then asleep.
  const std::int64_t spin_until = monotonic_now_ns() + kSpinForReplyNs;
  while (calls.done.load(std::memory_order_acquire) == seen) {
    const std::int64_t now = monotonic_now_ns();
    const std::int64_t left = deadline - now;
    if (left <= 0) return false;
    if (now < spin_until) continue;
    futex_wait(calls.done, seen, left);
  }
  result = calls.result;
  return true;
}

DeviceStatus DriverDevice::read(DeviceReading& reading) {
  if (hung()) return DeviceStatus::kError;
  int result = HAPTIC_DRIVER_FAILED;
  if (!call(kRead, result)) {
    hung_.store(true, std::memory_order_release);
    api_->enter_safe_state(driver_);
    return DeviceStatus::kError;
  }
  if (result != HAPTIC_DRIVER_OK) return DeviceStatus::kError;
  const haptic_driver_reading& sample = calls_->reading;
  const std::uint32_t n = info_.joints;
  for (std::uint32_t i = 0; i < n; ++i) {
    reading.q[i] = sample.q[i];
    reading.q_dot[i] = sample.q_dot[i];
    reading.tau_sensor[i] = sample.tau_sensor[i];
  }
  reading.F_sensor_W = {sample.force_sensor_W[0], sample.force_sensor_W[1], sample.force_sensor_W[2]};
  reading.buttons = info_.buttons >= 32 ? sample.buttons
                                        : sample.buttons & ((std::uint32_t{1} << info_.buttons) - 1);
  reading.safe_state = sample.safe_state != 0;
  if (description_.capabilities.orientation) {
    const double* q = sample.orientation_W;
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm >= 0.5 && norm <= 2.0)) return DeviceStatus::kError;  // NaN lands here too
    reading.R_WT = {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
    if (api_->abi_version >= 2 && description_.capabilities.measured_rates) {
      const double* w = sample.angular_velocity_W;
      reading.w_WT = {w[0], w[1], w[2]};  // DevicePort refuses a non-finite one
    }
  }
  // A device that stopped sampling repeats its last reading: after stale_after still ticks, a fault.
  if (options_.stale_after > 0) {
    if (have_sequence_ && sample.sequence == last_sequence_) {
      if (++still_ticks_ >= options_.stale_after) {
        ++stale_readings_;
        return DeviceStatus::kError;
      }
    } else {
      still_ticks_ = 0;
    }
    last_sequence_ = sample.sequence;
    have_sequence_ = true;
  }
  return DeviceStatus::kOk;
}

DeviceStatus DriverDevice::write(const DeviceCommand& command, double dt) {
  if (hung()) return DeviceStatus::kError;
  for (std::uint32_t i = 0; i < HAPTIC_DRIVER_MAX_JOINTS; ++i) {
    calls_->command.tau[i] = command.tau[i];
    calls_->command.brake[i] = command.brake[i];
  }
  if (description_.capabilities.torque) {
    calls_->command.torque_W[0] = command.tau_W.x;
    calls_->command.torque_W[1] = command.tau_W.y;
    calls_->command.torque_W[2] = command.tau_W.z;
  }
  calls_->dt = dt;
  int result = HAPTIC_DRIVER_FAILED;
  if (!call(kWrite, result)) {
    hung_.store(true, std::memory_order_release);
    api_->enter_safe_state(driver_);
    return DeviceStatus::kError;
  }
  return result == HAPTIC_DRIVER_OK ? DeviceStatus::kOk : DeviceStatus::kError;
}

void DriverDevice::enter_safe_state() { api_->enter_safe_state(driver_); }

std::string DriverDevice::fault_reason() const {
  if (hung()) {
    return "a driver call took longer than " + std::to_string(std::lround(options_.call_timeout_s * 1e3)) +
           " ms (call_timeout_ms); the device stays faulted until hapticd restarts";
  }
  if (api_->abi_version < 2 || api_->last_error == nullptr) return {};
  char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
  api_->last_error(driver_, error);
  error[HAPTIC_DRIVER_ERROR_SIZE - 1] = '\0';
  return error;
}

bool DriverDevice::run(Tick tick, void* context) {
  struct Trampoline {
    Tick tick;
    void* context;
    static int call(void* self, std::int64_t now_ns) {
      auto* t = static_cast<Trampoline*>(self);
      return t->tick(t->context, now_ns) ? 1 : 0;
    }
  } trampoline{tick, context};
  if (api_->run_servo == nullptr) return false;
  return api_->run_servo(driver_, &Trampoline::call, &trampoline) == HAPTIC_DRIVER_OK;
}

}  // namespace haptic::runtime
