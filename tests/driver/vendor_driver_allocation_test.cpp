// The vendor drivers allocate nothing on the loop: with their calls made on the calling thread
// (call timeout 0, as hapticd makes them when told to) 1,000 ticks of read and write through
// DriverDevice count no heap allocation on that thread. The stand-ins' own call logs allocate, so
// they are turned off here (`log off`); the Force Dimension stand-in's calls run on this thread,
// the OpenHaptics stand-in's servo loop on its own (allocations there are not the loop's).
#include <gtest/gtest.h>

#include <dlfcn.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include "support/allocation_counter.hpp"
#include "driver_test_support.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

/// Runs `ticks` read + write pairs and returns the allocations they made on this thread.
std::uint64_t allocations_over_ticks(DriverDevice& device, int ticks) {
  DeviceReading reading;
  DeviceCommand command;
  command.tau[2] = 0.01;
  // Warm up: the first calls may set up what the device keeps.
  for (int k = 0; k < 10; ++k) {
    device.read(reading);
    device.write(command, kT);
  }
  haptic::test::CountAllocations counting;
  haptic::test::reset_allocations();
  for (int k = 0; k < ticks; ++k) {
    EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_EQ(device.write(command, kT), DeviceStatus::kOk);
  }
  return haptic::test::allocations();
}

int (*control_of(const char* library, const char* symbol))(const char*) {
  void* handle = dlopen(library, RTLD_NOW | RTLD_LOCAL);  // the instance the driver loaded
  return handle == nullptr ? nullptr : reinterpret_cast<int (*)(const char*)>(dlsym(handle, symbol));
}

TEST(VendorDriverAllocations, TheForceDimensionDriverAllocatesNothingPerTick) {
  setenv("FAKE_DHD_DEVICES", "omega.7", 1);
  DriverOptions options = test::driver_options(
      FORCEDIMENSION_DRIVER, std::string(R"({"library": ")") + FAKE_FORCEDIMENSION_LIBRARY + "\"}");
  options.call_timeout_s = 0.0;
  DriverDevice device(options);
  const auto control = control_of(FAKE_FORCEDIMENSION_LIBRARY, "fake_dhd_control");
  ASSERT_NE(control, nullptr);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(control("log off"), 0);
  EXPECT_EQ(allocations_over_ticks(device, 1000), 0u);
  device.stop();
}

TEST(VendorDriverAllocations, TheOpenHapticsDriverAllocatesNothingPerTick) {
  setenv("FAKE_HD_DEVICES", "rig=Touch", 1);
  unsetenv("FAKE_HD_CLOCK");
  DriverOptions options = test::driver_options(
      OPENHAPTICS_DRIVER,
      std::string(R"({"device": "rig", "library": ")") + FAKE_OPENHAPTICS_LIBRARY + "\"}");
  options.call_timeout_s = 0.0;
  options.stale_after = 0;  // the ticks here come faster than the servo loop's samples
  DriverDevice device(options);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  // The servo loop's first samples: a read fails until its thread has run (polled, at most 10 s;
  // a loaded machine may not run a new thread for a while).
  DeviceReading first;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (device.read(first) != DeviceStatus::kOk && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(device.read(first), DeviceStatus::kOk) << "the servo loop gave no sample in 10 s";
  EXPECT_EQ(allocations_over_ticks(device, 1000), 0u);
  device.stop();
}

}  // namespace
}  // namespace haptic::runtime
