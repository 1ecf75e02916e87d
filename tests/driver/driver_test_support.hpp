#pragma once
// What the driver tests share: a driver's options for a library and params, and the refusal
// hapticd's DriverDevice gives when it will not load one.

#include <stdexcept>
#include <string>

#include "runtime/driver_device.hpp"

namespace haptic::runtime::test {

inline DriverOptions driver_options(const std::string& library, const std::string& params_json) {
  DriverOptions options;
  options.library = library;
  options.params_json = params_json;
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

}  // namespace haptic::runtime::test
