#pragma once
// What every vendor driver's C entry points share: nothing thrown inside a driver (by its JSON
// library, the standard library, a vendor runtime's C++ wrapper) may cross the C ABI into hapticd,
// where it would end the process. Each entry point runs its body through one of these: an
// exception becomes the driver's failure, said through `last_error`, and the call's error status.

#include <exception>
#include <string>

#include <haptic/driver.h>

namespace haptic::vendor {

/// Runs `body` (returning a HAPTIC_DRIVER_* status); an exception is recorded with `fail(what)`
/// and the call returns HAPTIC_DRIVER_FAILED.
template <typename Fail, typename Body>
int guarded(Fail&& fail, Body&& body) noexcept {
  try {
    return body();
  } catch (const std::exception& error) {
    try {
      fail(std::string("the driver failed: ") + error.what());
    } catch (...) {
    }
  } catch (...) {
    try {
      fail("the driver failed: an exception that is not a std::exception");
    } catch (...) {
    }
  }
  return HAPTIC_DRIVER_FAILED;
}

/// The same for an entry point that returns nothing (stop, enter_safe_state, set_log): an
/// exception is recorded and the call returns.
template <typename Fail, typename Body>
void guarded_void(Fail&& fail, Body&& body) noexcept {
  (void)guarded(fail, [&] {
    body();
    return HAPTIC_DRIVER_OK;
  });
}

}  // namespace haptic::vendor
