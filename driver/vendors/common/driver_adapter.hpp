#pragma once
// One adapter between hapticd's C driver ABI (<haptic/driver.h>) and a vendor driver written as a
// C++ class: the function table, every C entry point, the params (unknown keys refused), create's
// refusal, list_devices' text, hapticd's log, and the rule that nothing thrown inside a driver (by
// its JSON library, the standard library, a vendor runtime) crosses the C ABI into hapticd, where
// it would end the process. Each entry point catches everything; what it caught becomes the call's
// failure (HAPTIC_DRIVER_FAILED, a refusal, -1 devices) and the text last_error gives.
//
// A driver writes its device as a class derived from VendorDevice with these members (all but the
// two constants declared by HAPTIC_VENDOR_DEVICE(Class) in the class), and names it once with
// HAPTIC_VENDOR_DRIVER(Class) at namespace scope:
//
//   static constexpr const char* kParams[] = {...};     // the params keys it takes
//   static constexpr bool kDeviceClocked = ...;          // run_servo present (device-clocked mode)
//   static std::unique_ptr<Class> open(const DriverParams&);  // create(); throws Refusal to refuse
//                                                        // (common/driver_params.hpp)
//   static int list_devices(const DriverParams&, std::string& out);  // driver.h's list_devices
//   void describe(haptic_driver_info&) const;            // info arrives zeroed
//   int start();  void stop();
//   int read(haptic_driver_reading&);  int write(const haptic_driver_command&, double dt);
//   void enter_safe_state();                             // callable beside a late read or write
//   int run_servo(haptic_driver_tick_fn, void*);         // only where kDeviceClocked
//   void last_error(char* error) const;                  // its own failure; "" when none
//
// Its destructor releases the device and the runtime; runtime calls there that may throw go
// through `quietly`, since an exception leaving a destructor ends the process.
// Header-only and C++17 (the Haply driver's websocketpp does not compile as C++20).

#include <atomic>
#include <cstddef>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <haptic/driver.h>

#include "common/driver_params.hpp"

namespace haptic::vendor {

/// Runs `body`, swallowing whatever it throws: for a destructor's runtime calls.
template <typename Body>
void quietly(Body&& body) noexcept {
  try {
    body();
  } catch (...) {
  }
}

/// What the adapter keeps for every device: hapticd's log and the failure an entry point caught.
class VendorDevice {
 public:
  VendorDevice() = default;
  VendorDevice(const VendorDevice&) = delete;
  VendorDevice& operator=(const VendorDevice&) = delete;

  /// Says `message` in hapticd's log (not from read or write: the log may allocate).
  void say(int level, const std::string& message) const {
    if (log_ != nullptr) log_(log_context_, level, message.c_str());
  }

 private:
  template <typename Device>
  friend class DriverAdapter;

  /// An entry point caught `what`: it is the device's most recent failure until the next read,
  /// write or start returns on its own.
  void caught(const char* what) noexcept {
    std::lock_guard lock(caught_mutex_);
    std::snprintf(caught_text_, sizeof caught_text_, "the driver failed: %s", what);
    threw_.store(true, std::memory_order_release);
  }
  /// A call returned on its own (the loop's path: one relaxed load, no store while nothing threw).
  void returned() noexcept {
    if (threw_.load(std::memory_order_relaxed)) threw_.store(false, std::memory_order_relaxed);
  }
  /// Copies the caught failure into `error`; false when the most recent call did not throw.
  bool caught_error(char* error) const noexcept {
    if (!threw_.load(std::memory_order_acquire)) return false;
    std::lock_guard lock(caught_mutex_);
    std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", caught_text_);
    return true;
  }

  haptic_driver_log_fn log_ = nullptr;
  void* log_context_ = nullptr;
  std::atomic<bool> threw_{false};
  mutable std::mutex caught_mutex_;  // taken only where something threw, and by last_error
  char caught_text_[HAPTIC_DRIVER_ERROR_SIZE] = {};
};

/// The text of the exception being handled (inside a catch block).
inline const char* current_exception_text() noexcept {
  try {
    throw;
  } catch (const std::exception& error) {
    return error.what();
  } catch (...) {
    return "an exception that is not a std::exception";
  }
}

/// `Device`'s C function table (the header comment says what `Device` provides).
template <typename Device>
class DriverAdapter {
 public:
  static const haptic_driver_api* api() noexcept {
    static const haptic_driver_api table = {
        HAPTIC_DRIVER_ABI_VERSION,
        sizeof(haptic_driver_info),
        sizeof(haptic_driver_reading),
        sizeof(haptic_driver_command),
        create,
        destroy,
        describe,
        start,
        stop,
        read,
        write,
        enter_safe_state,
        servo_entry(),
        set_log,
        list_devices,
        last_error,
    };
    return &table;
  }

 private:
  static Device& of(void* driver) { return *static_cast<Device*>(driver); }

  /// Runs an entry point's body; what it throws is the device's failure and the call fails.
  template <typename Body>
  static int guarded(Device& device, Body&& body) noexcept {
    try {
      const int result = body();
      device.returned();
      return result;
    } catch (...) {
      device.caught(current_exception_text());
      return HAPTIC_DRIVER_FAILED;
    }
  }

  static void* create(const char* params_json, char* error) noexcept {
    try {
      const DriverParams params(params_json != nullptr ? params_json : "{}", Device::kParams);
      std::unique_ptr<Device> device = Device::open(params);
      return device.release();
    } catch (...) {
      // A refusal (the driver's, or the params') in its own words; anything else says it threw.
      const char* what = current_exception_text();
      bool refused = false;
      try {
        throw;
      } catch (const Refusal&) {  // params' errors too
        refused = true;
      } catch (...) {
      }
      std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s%s", refused ? "" : "the driver failed: ", what);
      return nullptr;
    }
  }

  static void destroy(void* driver) noexcept { delete static_cast<Device*>(driver); }

  static int describe(void* driver, haptic_driver_info* info) noexcept {
    Device& device = of(driver);
    return guarded(device, [&] {
      *info = haptic_driver_info{};
      device.describe(*info);
      return HAPTIC_DRIVER_OK;
    });
  }

  static int start(void* driver) noexcept {
    Device& device = of(driver);
    return guarded(device, [&] { return device.start(); });
  }

  static void stop(void* driver) noexcept {
    Device& device = of(driver);
    (void)guarded(device, [&] {
      device.stop();
      return HAPTIC_DRIVER_OK;
    });
  }

  static int read(void* driver, haptic_driver_reading* reading) noexcept {
    Device& device = of(driver);
    return guarded(device, [&] { return device.read(*reading); });
  }

  static int write(void* driver, const haptic_driver_command* command, double dt) noexcept {
    Device& device = of(driver);
    return guarded(device, [&] { return device.write(*command, dt); });
  }

  static void enter_safe_state(void* driver) noexcept {
    Device& device = of(driver);
    (void)guarded(device, [&] {
      device.enter_safe_state();
      return HAPTIC_DRIVER_OK;
    });
  }

  static int run_servo(void* driver, haptic_driver_tick_fn tick, void* context) noexcept {
    Device& device = of(driver);
    return guarded(device, [&] { return device.run_servo(tick, context); });
  }
  using RunServo = int (*)(void*, haptic_driver_tick_fn, void*);
  static RunServo servo_entry() noexcept {
    if constexpr (Device::kDeviceClocked) {
      return &run_servo;
    } else {
      return nullptr;  // server-clocked: hapticd's loop calls read and write
    }
  }

  static void set_log(void* driver, haptic_driver_log_fn log, void* context) noexcept {
    Device& device = of(driver);
    device.log_ = log;
    device.log_context_ = context;
  }

  static int list_devices(const char* params_json, char* list, std::size_t size) noexcept {
    if (list == nullptr || size == 0) return -1;
    try {
      const DriverParams params(params_json != nullptr ? params_json : "{}", Device::kParams);
      std::string out;
      const int found = Device::list_devices(params, out);
      std::snprintf(list, size, "%s", out.c_str());
      return found;
    } catch (...) {
      std::snprintf(list, size, "%s", current_exception_text());
      return -1;
    }
  }

  static void last_error(void* driver, char* error) noexcept {
    const Device& device = of(driver);
    try {
      if (!device.caught_error(error)) device.last_error(error);
    } catch (...) {
      std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", current_exception_text());
    }
  }
};

}  // namespace haptic::vendor

/// Declares, inside `Device`'s class, the members the adapter calls (the driver defines them; a
/// device-clocked one declares run_servo beside them).
#define HAPTIC_VENDOR_DEVICE(Device)                                                          \
  static std::unique_ptr<Device> open(const ::haptic::vendor::DriverParams& params);          \
  static int list_devices(const ::haptic::vendor::DriverParams& params, std::string& out);    \
  void describe(haptic_driver_info& info) const;                                              \
  int start();                                                                                \
  void stop();                                                                                \
  int read(haptic_driver_reading& reading);                                                   \
  int write(const haptic_driver_command& command, double dt);                                 \
  void enter_safe_state();                                                                    \
  void last_error(char* error) const

/// Exports `Device` (a class written as driver_adapter.hpp says) as hapticd's driver entry point.
#define HAPTIC_VENDOR_DRIVER(Device)                                             \
  extern "C" HAPTIC_DRIVER_EXPORT const haptic_driver_api* haptic_driver_entry(void) { \
    return ::haptic::vendor::DriverAdapter<Device>::api();                       \
  }
