// The Force Dimension driver (driver/vendors/forcedimension) end to end against the stand-in of
// the vendor's runtime (tests/driver/standins: libdrd.so.3 over a simulated plant): the real
// driver code, loaded by hapticd's DriverDevice as hapticd loads it, the stand-in in place of the
// SDK. What this cannot show is said in docs/devices.md ("Force Dimension").
#include <gtest/gtest.h>

#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "driver_kit.hpp"
#include "driver_test_support.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

/// The stand-in with `devices` attached (FAKE_DHD_DEVICES, e.g. "omega.7,falcon"), reset.
class Standin : public test::StandinLibrary {
 public:
  explicit Standin(const std::string& devices) : test::StandinLibrary(configure(devices), "fake_dhd") {}

 private:
  static const char* configure(const std::string& devices) {
    setenv("FAKE_DHD_DEVICES", devices.c_str(), 1);  // read by the stand-in's reset
    return FAKE_FORCEDIMENSION_LIBRARY;
  }
};

std::string params(const std::string& extra = {}) {
  return std::string(R"({"library": ")") + FAKE_FORCEDIMENSION_LIBRARY + "\"" +
         (extra.empty() ? "" : ", " + extra) + "}";
}

DriverOptions fd(const std::string& extra = {}) { return test::driver_options(FORCEDIMENSION_DRIVER, params(extra)); }

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

TEST(ForceDimension, OpensCalibratesAndClosesInTheVendorsOrder) {
  Standin standin("omega.3");
  {
    DriverDevice device(fd());
    const DeviceDescription& d = device.description();
    EXPECT_NE(d.name.find("Force Dimension omega.3"), std::string::npos) << d.name;
    EXPECT_EQ(d.max_force, 12.0);  // CHAI3D's figure (SOURCES.md §1.7)
    EXPECT_EQ(d.workspace_max.x, 0.075);
    EXPECT_FALSE(d.capabilities.orientation);
    EXPECT_EQ(d.apparent_mass, 0.0);  // Force Dimension publishes none: unknown unless given
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    device.stop();
  }
  // Open the first device, calibrate it (RESET mode: drdAutoInit, then the robotic controller
  // stopped), the SDK's gravity compensation, forces on; at the end zero force, stop, close.
  EXPECT_TRUE(in_order(standin.calls(), {"dhdGetDeviceCount", "dhdOpenID 0", "drdIsInitialized 0",
                                         "drdAutoInit 0", "drdStop 1 0", "dhdSetGravityCompensation 1 0",
                                         "dhdEnableForce 1 0", "dhdSetForce 0 0 0 0", "dhdStop 0",
                                         "dhdClose 0"}));
}

TEST(ForceDimension, PassesTheDriverKit) {
  Standin standin("omega.3");
  std::ostringstream log;
  for (const auto& result : driver_kit::run_kit({FORCEDIMENSION_DRIVER, params(), true, test::kTestCallTimeoutS}, log)) {
    EXPECT_TRUE(result.passed) << result.name << ": " << result.detail << "\n" << log.str();
  }
}

// A wall rendered through the Cartesian model holds the stand-in's 1 N "hand" where a 500 N/m
// spring must: 2 mm deep (units and axes as the loop sees them: m in, N out).
TEST(ForceDimension, AWallHoldsAHandWhereTheSpringSays) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  CartesianModel model;
  DevicePort port(device, model);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("hand 0 0 0 -1"), 0);
  ToolReading tool;
  for (int k = 0; k < 4000; ++k) {
    ASSERT_EQ(port.read(tool), DeviceStatus::kOk) << "tick " << k;
    const double z = tool.p_WT.z;
    const engine::Vec3 F{0.0, 0.0, z < 0.0 ? -500.0 * z - 5.0 * tool.v_WT.z : 0.0};
    ASSERT_EQ(port.write(ToolCommand{F}, kT), DeviceStatus::kOk);
  }
  EXPECT_NEAR(tool.p_WT.z, -1.0 / 500.0, 2e-5);
  EXPECT_NEAR(tool.p_WT.x, 0.0, 1e-9);
  device.stop();
}

TEST(ForceDimension, AnUnpluggedDeviceFaultsNamingTheVendorsErrorAndComesBackWhenReplugged) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_EQ(device.fault_reason(), "");
  ASSERT_EQ(standin.control("unplug 0"), 0);
  EXPECT_EQ(device.read(reading), DeviceStatus::kError);
  const std::string why = device.fault_reason();
  EXPECT_EQ(why.rfind("dhdGetPosition: ", 0), 0u) << why;
  EXPECT_NE(why.find("(DHD error 2)"), std::string::npos) << why;  // DHD_ERROR_COM (SOURCES.md §1.5)
  ASSERT_EQ(standin.control("replug 0"), 0);
  standin.clear();
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);  // back, without a restart
  EXPECT_TRUE(in_order(standin.calls(), {"dhdGetPosition 0", "dhdEnableForce 1 0"}));
  DeviceCommand push;
  push.tau[0] = 1.0;
  const double x0 = reading.q[0];
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  }
  EXPECT_GT(reading.q[0], x0);  // forces are on again
  device.stop();
}

TEST(ForceDimension, AHungCallTimesOutAndTheDeviceStaysFaulted) {
  Standin standin("omega.3");
  DriverOptions options = fd();
  options.call_timeout_s = 0.5;  // a true hang: the stand-in never answers
  DriverDevice device(options);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("hang 0"), 0);
  EXPECT_EQ(device.read(reading), DeviceStatus::kError);
  EXPECT_TRUE(device.hung());
  EXPECT_NE(device.fault_reason().find("longer than 500 ms"), std::string::npos) << device.fault_reason();
  ASSERT_EQ(standin.control("release"), 0);
  device.stop();
}

// An omega.7's passive wrist and gripper are read; a sigma.7's active wrist takes the torque and
// its gripper the force, through the driver's table as hapticd calls it.
TEST(ForceDimension, WristsAndGrippersAreReadAndAnActiveWristTakesTorque) {
  {
    Standin standin("omega.7");
    DriverDevice device(fd());
    EXPECT_TRUE(device.description().capabilities.orientation);
    EXPECT_FALSE(device.info().capabilities & HAPTIC_DRIVER_TORQUE_OUTPUT);
    EXPECT_TRUE(device.info().capabilities & HAPTIC_DRIVER_GRIPPER);
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    ASSERT_EQ(standin.control("turn 0 0 0 0.5"), 0);  // 0.5 rad about z
    DeviceReading reading;
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_NEAR(reading.R_WT.w, std::cos(0.25), 1e-9);
    EXPECT_NEAR(reading.R_WT.z, std::sin(0.25), 1e-9);
    device.stop();
  }
  Standin standin("sigma.7");
  void* library = dlopen(FORCEDIMENSION_DRIVER, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(library, nullptr) << dlerror();
  const auto* api = reinterpret_cast<haptic_driver_entry_fn>(dlsym(library, HAPTIC_DRIVER_ENTRY_SYMBOL))();
  char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
  void* driver = api->create(params().c_str(), error);
  ASSERT_NE(driver, nullptr) << error;
  haptic_driver_info info{};
  ASSERT_EQ(api->describe(driver, &info), HAPTIC_DRIVER_OK);
  EXPECT_TRUE(info.capabilities & HAPTIC_DRIVER_TORQUE_OUTPUT);
  EXPECT_EQ(info.max_torque, 0.2);  // CHAI3D's figure (SOURCES.md §1.7)
  EXPECT_EQ(info.gripper_max_force, 8.0);
  ASSERT_EQ(api->start(driver), HAPTIC_DRIVER_OK);
  haptic_driver_command command{};
  command.tau[2] = 1.5;
  command.torque_W[0] = 0.1;
  command.gripper_force = 2.0;
  standin.clear();
  ASSERT_EQ(api->write(driver, &command, kT), HAPTIC_DRIVER_OK);
  EXPECT_TRUE(in_order(standin.calls(), {"dhdSetForceAndTorqueAndGripperForce 0 0 1.5 0.1 0 0 2 0"}));
  haptic_driver_reading reading{};
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(api->write(driver, &command, kT), HAPTIC_DRIVER_OK);
    ASSERT_EQ(api->read(driver, &reading), HAPTIC_DRIVER_OK);
  }
  EXPECT_GT(reading.angular_velocity_W[0], 0.0);  // the torque about +x turns the wrist about +x
  EXPECT_GT(reading.orientation_W[1], 0.0);
  api->stop(driver);
  api->destroy(driver);
  dlclose(library);
}

TEST(ForceDimension, ListsEveryDeviceWithTheParamsThatOpenIt) {
  Standin standin("omega.7,falcon");
  const DriverListing listing = list_driver_devices(FORCEDIMENSION_DRIVER, params());
  ASSERT_EQ(listing.error, "");
  ASSERT_EQ(listing.devices.size(), 2u);
  EXPECT_EQ(listing.devices[0].params_json, R"({"index": 0})");
  EXPECT_NE(listing.devices[0].description.find("omega.7"), std::string::npos) << listing.devices[0].description;
  EXPECT_EQ(listing.devices[1].params_json, R"({"index": 1})");
  EXPECT_NE(listing.devices[1].description.find("serial 65535"), std::string::npos)  // a Falcon (§1.6)
      << listing.devices[1].description;
  // The second opens as listed: the Falcon, with its four buttons.
  DriverDevice falcon(fd(R"("index": 1)"));
  EXPECT_EQ(falcon.description().buttons, 4u);
  EXPECT_EQ(falcon.description().max_force, 8.0);
}

TEST(ForceDimension, WhatIsMissingOrWrongIsRefusedSayingWhatToDo) {
  Standin standin("omega.3");
  DriverOptions nowhere;
  nowhere.library = FORCEDIMENSION_DRIVER;
  nowhere.params_json = R"({"library": "/nonexistent/libdrd.so.3"})";
  EXPECT_NE(refusal(nowhere).find("params.library: cannot load /nonexistent/libdrd.so.3"), std::string::npos)
      << refusal(nowhere);
  EXPECT_NE(refusal(fd(R"("index": 5)")).find("params.index 5: 1 device connected, index 0"), std::string::npos)
      << refusal(fd(R"("index": 5)"));
  EXPECT_NE(refusal(fd(R"("idx": 0)")).find("params.idx: not an option of this driver"), std::string::npos)
      << refusal(fd(R"("idx": 0)"));
  // Without calibration allowed, an uncalibrated device does not start, and says why.
  DriverDevice device(fd(R"("calibrate": false)"));
  EXPECT_EQ(device.start(), DeviceStatus::kError);
  EXPECT_EQ(device.fault_reason(), "the device is not calibrated and params.calibrate is false");
}

}  // namespace
}  // namespace haptic::runtime
