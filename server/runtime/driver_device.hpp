#pragma once
// A device behind a driver library (driver/include/haptic/driver.h), loaded with dlopen: real
// hardware, or a plant of one's own. The library is checked before anything is called (the entry
// symbol, the ABI version, the structs' sizes) and its description validated; every refusal names
// the library and what was wrong.
//
// Server-clocked (the default), read() and write() are carried out on a driver thread of their
// own while the loop waits for at most the call timeout: a call that takes longer — a vendor
// library that hangs — is a device fault, the driver's enter_safe_state() is called at once from
// the loop, and the device stays faulted (every later read and write is an error at once) so the
// loop goes on publishing and commanding nothing. With a timeout of 0 the calls are made on the
// loop itself (no thread hop, no protection). A reading whose sequence number has not moved for
// stale_after ticks is a fault too (a device that stopped sampling).
// Device-clocked (the driver's run_servo() owns the servo loop), the loop's ticks run inside the
// driver's callback (ServoClock) and read() and write() call the driver directly.

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptic/driver.h"
#include "runtime/device.hpp"
#include "runtime/servo_clock.hpp"

namespace haptic::runtime {

struct DriverOptions {
  std::string library;             // path of the shared library
  std::string params_json = "{}";  // handed to the driver's create()
  /// Longest a read or write may take before it is a device fault; 0: call on the loop. Unit: s.
  double call_timeout_s = 0.02;
  /// Ticks a reading's sequence may stay still before it is a fault; 0: not checked.
  std::uint32_t stale_after = 3;
  bool device_clocked = false;     // the driver's run_servo() paces the loop
  /// The SCHED_FIFO priority the driver thread asks for (and memory locked), as the loop's: the
  /// loop waits on that thread every tick. 0: normal scheduling (lockstep, or FIFO turned off).
  int thread_priority = 0;
  /// The device's figures measured on the bench, in place of the driver's (DriverConfig.profile):
  /// per axis of W the apparent mass (kg) and damping (N·s/m), and the delay beyond a perfect
  /// loop's (s). Unset: the driver's own.
  struct Profile {
    std::array<double, 3> apparent_mass{}, apparent_damping{};
    double delay_s = 0.0;
    double actuator_lag_s = 0.0;
  };
  std::optional<Profile> profile;
  /// Where the driver's own messages go (ABI 2's set_log): level HAPTIC_DRIVER_LOG_*, the text.
  /// Unset: dropped.
  std::function<void(int level, const std::string& message)> log;
};

/// The folders holding hapticd's drivers, in order: each of `extra` (hapticd --driver-dir), the
/// installed ones (<prefix>/<libdir>/hapticd beside the binary's bin/), and, for a hapticd run
/// from its build tree, that tree's driver/. Missing folders are left out.
std::vector<std::string> driver_folders(const std::vector<std::string>& extra = {});

/// `library` as DriverDevice loads it: a name without a '/' found in driver_folders() becomes
/// that file's path; anything else stays as it is (dlopen then searches as dlopen(3) does).
std::string resolve_driver_library(const std::string& library);

/// What one driver library says it can open on this host (ABI 2's list_devices), for
/// `hapticd --list-devices`.
struct DriverListing {
  bool is_driver = false;         // it exports haptic_driver_entry()
  std::uint32_t abi_version = 0;  // 0: not one hapticd loads (`error` says why)
  bool can_list = false;          // it has list_devices (version 2 drivers may leave it NULL)
  struct Entry {
    std::string params_json;  // what "params" must say to open it
    std::string description;
  };
  std::vector<Entry> devices;
  std::string error;  // it could not be asked, or could not ask its vendor's runtime (why)
};
/// Loads `library`, checks its entry and ABI version as DriverDevice does, and asks it (without
/// create()). Never throws.
DriverListing list_driver_devices(const std::string& library, const std::string& params_json = "{}");

/// The sizes of the ABI's structs as a driver of `abi_version` has them (version 2 only appended
/// to version 1's); 0 for a version hapticd does not load.
struct DriverStructSizes {
  std::size_t info = 0, reading = 0, command = 0;
};
DriverStructSizes driver_struct_sizes(std::uint32_t abi_version);

class DriverDevice final : public Device, public ServoClock {
 public:
  /// Loads, checks and creates the driver. Throws std::runtime_error naming the library and the
  /// reason (cannot load, no entry symbol, ABI or struct size mismatch, create() refused, a bad
  /// description, device-clocked without run_servo or a servo rate).
  explicit DriverDevice(const DriverOptions& options);
  ~DriverDevice() override;
  DriverDevice(const DriverDevice&) = delete;
  DriverDevice& operator=(const DriverDevice&) = delete;

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus start() override;
  void stop() override;
  DeviceStatus read(DeviceReading& reading) override;
  DeviceStatus write(const DeviceCommand& command, double dt) override;
  void enter_safe_state() override;
  /// ABI 2's last_error (a call that hung: says so); "" for a version 1 driver.
  std::string fault_reason() const override;

  /// Device-clocked: the driver's servo rate. Unit: Hz.
  double rate_hz() const override { return info_.servo_rate_hz; }
  bool run(Tick tick, void* context) override;

  /// True once a call has outlasted the timeout (latched until the server restarts).
  bool hung() const { return hung_.load(std::memory_order_acquire); }
  /// The driver thread is running (between start() and a stop() that could join it; a call
  /// that never came back keeps it).
  bool driver_thread_running() const { return thread_.joinable(); }
  /// Readings refused as stale so far.
  std::uint64_t stale_readings() const { return stale_readings_; }
  /// The ABI version the library was built for (1 or 2).
  std::uint32_t abi_version() const { return api_->abi_version; }
  /// What the driver described (version 2 fields 0 for a version 1 driver).
  const haptic_driver_info& info() const { return info_; }

 private:
  enum Call : std::uint32_t { kNone = 0, kRead = 1, kWrite = 2, kQuit = 3 };
  /// What the loop and the driver thread share. On the heap: when a call never comes back the
  /// thread is left running with it, and it must outlive this device.
  struct CallState {
    const haptic_driver_api* api = nullptr;
    void* driver = nullptr;
    // The call in flight: written by the loop before the request, by the thread before done.
    haptic_driver_reading reading{};
    haptic_driver_command command{};
    double dt = 0.0;
    int result = 0;
    std::atomic<std::uint32_t> request{kNone};
    std::atomic<std::uint32_t> done{0};  // bumped when a call completes (a futex word)
    /// The driver's messages (set_log) go here; kept with the state, which outlives a hung call.
    std::function<void(int level, const std::string& message)> log;
    static void log_trampoline(void* self, int level, const char* message);

    int call_driver(Call what);
    void serve(int priority);  // the driver thread, at SCHED_FIFO `priority` where > 0
  };

  /// Runs `what` on the driver thread (or here, without a timeout or device-clocked); false when
  /// it timed out.
  bool call(Call what, int& result);

  DriverOptions options_;
  void* library_ = nullptr;
  const haptic_driver_api* api_ = nullptr;
  void* driver_ = nullptr;
  haptic_driver_info info_{};
  DeviceDescription description_;

  std::unique_ptr<CallState> calls_ = std::make_unique<CallState>();
  std::atomic<bool> hung_{false};
  bool started_ = false;
  std::thread thread_;

  std::uint64_t last_sequence_ = 0;
  std::uint32_t still_ticks_ = 0;
  std::uint64_t stale_readings_ = 0;
  bool have_sequence_ = false;
};

}  // namespace haptic::runtime
