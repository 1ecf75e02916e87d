#pragma once
// What the driver tests share: a driver's options for a library and params, and the refusal
// hapticd's DriverDevice gives when it will not load one.

#include <dlfcn.h>

#include <stdexcept>
#include <string>

#include "runtime/driver_device.hpp"

namespace haptic::runtime::test {

/// The driver-call deadline every test that does not test it runs with: what a call may take
/// before it is a hang (a fault for good). A loaded machine may leave the driver thread
/// unscheduled for longer than hapticd's 20 ms default; the behaviour these tests check does not
/// depend on the call's speed, so they wait as long as it takes (a real hang is still one).
inline constexpr double kTestCallTimeoutS = 5.0;

inline DriverOptions driver_options(const std::string& library, const std::string& params_json) {
  DriverOptions options;
  options.library = library;
  options.params_json = params_json;
  options.call_timeout_s = kTestCallTimeoutS;
  return options;
}

/// The message DriverDevice's constructor throws, or "" when it does not.
inline std::string refusal(const DriverOptions& options) {
  try {
    DriverDevice device(options);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return {};
}

/// A stand-in runtime's control API (tests/driver/standins/README.md), on the instance a driver
/// loaded (dlopen of the same path returns it): PREFIX_control, PREFIX_calls, PREFIX_clear_calls.
class StandinLibrary {
 public:
  StandinLibrary(const char* path, const std::string& prefix) {
    handle_ = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) throw std::runtime_error(dlerror());
    control_ = reinterpret_cast<int (*)(const char*)>(dlsym(handle_, (prefix + "_control").c_str()));
    calls_ = reinterpret_cast<const char* (*)()>(dlsym(handle_, (prefix + "_calls").c_str()));
    clear_ = reinterpret_cast<void (*)()>(dlsym(handle_, (prefix + "_clear_calls").c_str()));
    if (control_ == nullptr || calls_ == nullptr || clear_ == nullptr) {
      throw std::runtime_error(std::string(path) + " has no " + prefix + "_* control API");
    }
    if (control("reset") != 0) throw std::runtime_error("the stand-in refused reset");
    clear();
  }
  ~StandinLibrary() { dlclose(handle_); }
  StandinLibrary(const StandinLibrary&) = delete;
  StandinLibrary& operator=(const StandinLibrary&) = delete;

  int control(const std::string& command) const { return control_(command.c_str()); }
  std::string calls() const { return calls_(); }
  void clear() const { clear_(); }

 private:
  void* handle_ = nullptr;
  int (*control_)(const char*) = nullptr;
  const char* (*calls_)() = nullptr;
  void (*clear_)() = nullptr;
};

}  // namespace haptic::runtime::test
