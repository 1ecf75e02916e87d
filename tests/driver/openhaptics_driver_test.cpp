// The OpenHaptics driver (driver/vendors/openhaptics) end to end against the stand-in of the
// vendor's HD runtime (tests/driver/standins: libHD.so.3.4 over a simulated plant and scheduler):
// the real driver code, loaded by hapticd's DriverDevice as hapticd loads it. With the stand-in's
// manual clock (FAKE_HD_CLOCK=manual) a test ticks the servo loop itself, so the physics is exact;
// with its free-running scheduler, timing-dependent checks have loose bounds.
#include <gtest/gtest.h>

#include <dlfcn.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "driver_kit.hpp"
#include "driver_test_support.hpp"
#include "engine/core/rotation.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

/// The stand-in with `devices` attached (FAKE_HD_DEVICES, "name=model,..."), on its manual clock
/// (FAKE_HD_CLOCK=manual) or its free-running scheduler, reset.
class Standin : public test::StandinLibrary {
 public:
  Standin(const std::string& devices, bool manual)
      : test::StandinLibrary(configure(devices, manual), "fake_hd") {}

 private:
  static const char* configure(const std::string& devices, bool manual) {
    setenv("FAKE_HD_DEVICES", devices.c_str(), 1);
    if (manual) {
      setenv("FAKE_HD_CLOCK", "manual", 1);
    } else {
      unsetenv("FAKE_HD_CLOCK");
    }
    return FAKE_OPENHAPTICS_LIBRARY;
  }
};

std::string params(const std::string& extra = {}) {
  return std::string(R"({"library": ")") + FAKE_OPENHAPTICS_LIBRARY + "\"" +
         (extra.empty() ? "" : ", " + extra) + "}";
}

DriverOptions oh(const std::string& extra = {}) {
  return test::driver_options(OPENHAPTICS_DRIVER, params(extra));
}

using test::refusal;

/// True when each of `wanted` starts a line of `log`, in this order.
::testing::AssertionResult in_order(const std::string& log, const std::vector<std::string>& wanted) {
  std::istringstream lines(log);
  std::string line;
  std::size_t next = 0;
  while (next < wanted.size() && std::getline(lines, line)) {
    if (line.rfind(wanted[next], 0) == 0) ++next;
  }
  if (next == wanted.size()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << wanted[next] << "' missing (in this order) from:\n" << log;
}

TEST(OpenHaptics, InitialisesCalibratesRunsTheServoLoopAndStopsInTheVendorsOrder) {
  Standin standin("rig=Touch", true);
  {
    DriverDevice device(oh(R"("device": "rig")"));
    const DeviceDescription& d = device.description();
    EXPECT_NE(d.name.find("3D Systems Touch, serial "), std::string::npos) << d.name;
    EXPECT_EQ(d.max_force, 3.3);  // HD_NOMINAL_MAX_FORCE as the stand-in gives it (SOURCES.md §2.6)
    EXPECT_EQ(d.buttons, 2u);
    EXPECT_TRUE(d.capabilities.orientation);  // HD_INPUT_DOF 6: the gimbal's angles
    EXPECT_GT(d.workspace_max.z, d.workspace_min.z);
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    device.stop();
  }
  // Open by name, calibrate (the Touch's inkwell), forces on, the callback scheduled, the scheduler
  // started; at the end stopped, unscheduled, forces off, the device released (§2.3).
  EXPECT_TRUE(in_order(standin.calls(), {"hdInitDevice", "hdUpdateCalibration", "hdEnable 0x4000",
                                         "hdScheduleAsynchronous", "hdStartScheduler", "hdStopScheduler",
                                         "hdUnschedule", "hdDisable 0x4000", "hdDisableDevice"}));
}

// On the manual clock: a 500 N/m wall on W's z (up) holds the stand-in's 1 N hand pressing down
// (−y in the HD frame, which is up there) 2 mm deep: the axes and the mm-to-m units as the loop
// sees them.
TEST(OpenHaptics, AWallHoldsAHandWhereTheSpringSaysWithTheAxesOfW) {
  Standin standin("rig=Touch", true);
  DriverDevice device(oh(R"("device": "rig")"));
  CartesianModel model;
  DevicePort port(device, model);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("hand rig 0 -1 0"), 0);
  ToolReading tool;
  ASSERT_EQ(standin.control("tick 1"), 0);
  ASSERT_EQ(port.read(tool), DeviceStatus::kOk);
  const double z0 = tool.p_WT.z;
  for (int k = 0; k < 4000; ++k) {
    const double z = tool.p_WT.z - z0;
    const engine::Vec3 F{0.0, 0.0, z < 0.0 ? -500.0 * z - 5.0 * tool.v_WT.z : 0.0};
    ASSERT_EQ(port.write(ToolCommand{F}, kT), DeviceStatus::kOk);
    ASSERT_EQ(standin.control("tick 1"), 0);
    ASSERT_EQ(port.read(tool), DeviceStatus::kOk) << "tick " << k;
  }
  EXPECT_NEAR(tool.p_WT.z - z0, -1.0 / 500.0, 5e-5);
  device.stop();
}

// driver.h: after enter_safe_state the device holds zero force until the next write, which drives
// it again (the force goes out from the next servo frame), and returns OK. On the manual clock.
TEST(OpenHaptics, AfterTheSafeStateTheNextWriteDrivesTheDeviceAgain) {
  Standin standin("rig=Touch", true);
  DriverDevice device(oh(R"("device": "rig")"));
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("tick 1"), 0);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  DeviceCommand push;
  push.tau[0] = 0.5;  // N along W's x, the HD frame's z (SOURCES.md §2.5)
  const std::string pushed = "hdSetDoublev 0x2700 0 0 0.5\n", zero = "hdSetDoublev 0x2700 0 0 0\n";
  ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
  standin.clear();
  ASSERT_EQ(standin.control("tick 1"), 0);
  EXPECT_NE(standin.calls().find(pushed), std::string::npos) << standin.calls();
  device.enter_safe_state();
  standin.clear();
  ASSERT_EQ(standin.control("tick 2"), 0);
  EXPECT_NE(standin.calls().find(zero), std::string::npos) << standin.calls();
  EXPECT_EQ(standin.calls().find(pushed), std::string::npos) << standin.calls();
  ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
  standin.clear();
  ASSERT_EQ(standin.control("tick 1"), 0);
  EXPECT_NE(standin.calls().find(pushed), std::string::npos) << standin.calls();
  device.stop();
}

// The gimbal turned about each of HD's axes reads as the same turn about the matching axis of W
// (the one the position's axes map to: W x = HD z, W y = HD x, W z = HD y, SOURCES.md §2.5), on
// the manual clock.
TEST(OpenHaptics, TheGimbalsTurnAboutEachHdAxisIsATurnAboutTheMatchingAxisOfW) {
  Standin standin("rig=Touch", true);
  DriverDevice device(oh(R"("device": "rig")"));
  ASSERT_TRUE(device.description().capabilities.orientation);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  const struct {
    const char* turn;  // a rotation vector in HD's frame, rad
    engine::Vec3 in_w;
  } cases[] = {{"0.3 0 0", {0, 0.3, 0}}, {"0 0.3 0", {0, 0, 0.3}}, {"0 0 0.3", {0.3, 0, 0}},
               {"0.2 -0.1 0.25", {0.25, 0.2, -0.1}}};
  for (const auto& c : cases) {
    ASSERT_EQ(standin.control(std::string("turn rig ") + c.turn), 0) << c.turn;
    ASSERT_EQ(standin.control("tick 1"), 0);
    DeviceReading reading;
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk) << c.turn;
    const engine::Vec3 turned = engine::rotation_vector(reading.R_WT);
    EXPECT_NEAR(turned.x, c.in_w.x, 1e-9) << c.turn;
    EXPECT_NEAR(turned.y, c.in_w.y, 1e-9) << c.turn;
    EXPECT_NEAR(turned.z, c.in_w.z, 1e-9) << c.turn;
  }
  device.stop();
}

TEST(OpenHaptics, PassesTheDriverKitOnAFreeRunningServoLoop) {
  Standin standin("rig=Touch", false);
  std::ostringstream log;
  for (const auto& result : driver_kit::run_kit({OPENHAPTICS_DRIVER, params(R"("device": "rig")"), true, test::kTestCallTimeoutS}, log)) {
    EXPECT_TRUE(result.passed) << result.name << ": " << result.detail << "\n" << log.str();
  }
}

TEST(OpenHaptics, AnUnpluggedDeviceFaultsNamingTheRuntimesErrorAndComesBackWhenReplugged) {
  Standin standin("rig=Touch", true);
  DriverDevice device(oh(R"("device": "rig")"));
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(standin.control("tick 1"), 0);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("unplug rig"), 0);
  ASSERT_EQ(standin.control("tick 1"), 0);
  EXPECT_EQ(device.read(reading), DeviceStatus::kError);
  EXPECT_NE(device.fault_reason().find("(HD error 0x0302)"), std::string::npos)  // HD_COMM_ERROR (§2.4)
      << device.fault_reason();
  ASSERT_EQ(standin.control("replug rig"), 0);
  ASSERT_EQ(standin.control("tick 1"), 0);
  EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_EQ(device.fault_reason(), "");
  device.stop();
}

// Device-clocked, hapticd's tick runs inside the runtime's servo callback, once per servo tick of
// the free-running scheduler (1000 Hz), until the tick asks to stop.
TEST(OpenHaptics, DeviceClockedTheTickRunsInsideTheServoCallback) {
  Standin standin("rig=Touch", false);
  DriverOptions options = oh(R"("device": "rig")");
  options.device_clocked = true;
  DriverDevice device(options);
  EXPECT_EQ(device.rate_hz(), 1000.0);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  struct Context {
    DriverDevice* device;
    std::atomic<int> ticks{0};
    std::atomic<int> failed{0};
    std::atomic<bool> stop{false};
  } context{&device};
  auto tick = [](void* raw, std::int64_t /*now_ns*/) -> bool {
    auto* c = static_cast<Context*>(raw);
    DeviceReading reading;
    if (c->device->read(reading) != DeviceStatus::kOk) ++c->failed;
    if (c->device->write(DeviceCommand{}, kT) != DeviceStatus::kOk) ++c->failed;
    ++c->ticks;
    return c->stop.load();
  };
  std::thread servo([&] { EXPECT_TRUE(device.run(tick, &context)); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  context.stop = true;
  servo.join();
  EXPECT_GT(context.ticks.load(), 50);   // about 300 at 1 kHz; loose for a loaded machine
  EXPECT_LT(context.ticks.load(), 1000);
  EXPECT_EQ(context.failed.load(), 0);
  device.stop();
}

TEST(OpenHaptics, ListsTheDeviceAndRefusesWhatIsMissingSayingWhatToDo) {
  Standin standin("rig=Touch X", true);
  const DriverListing listing = list_driver_devices(OPENHAPTICS_DRIVER, params());
  ASSERT_EQ(listing.error, "");
  ASSERT_EQ(listing.devices.size(), 1u);
  EXPECT_EQ(listing.devices[0].params_json, "{}");
  EXPECT_NE(listing.devices[0].description.find("3D Systems Touch X"), std::string::npos)
      << listing.devices[0].description;
  DriverOptions nowhere = test::driver_options(OPENHAPTICS_DRIVER, R"({"library": "/nonexistent/libHD.so"})");
  EXPECT_NE(refusal(nowhere).find("params.library: cannot load /nonexistent/libHD.so"), std::string::npos)
      << refusal(nowhere);
  const std::string unknown = refusal(oh(R"("device": "nope")"));
  EXPECT_NE(unknown.find("hdInitDevice(\"nope\")"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("(HD error 0x0300)"), std::string::npos) << unknown;  // HD_DEVICE_FAULT (§2.3)
  EXPECT_NE(refusal(oh(R"("devise": "rig")")).find("params.devise: not an option of this driver"),
            std::string::npos);
}

}  // namespace
}  // namespace haptic::runtime
