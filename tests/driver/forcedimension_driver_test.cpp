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

/// The line of `log` right after the first line that starts with `line` ("" when none).
std::string line_after(const std::string& log, const std::string& line) {
  std::istringstream lines(log);
  std::string at;
  while (std::getline(lines, at)) {
    if (at.rfind(line, 0) == 0) return std::getline(lines, at) ? at : std::string();
  }
  return {};
}

/// Device 0's force state as the stand-in holds it (its dhdGetStatus, SOURCES.md §1.5 indices).
struct ForceState {
  int force = -1, brake = -1, cause = -1;
};
ForceState force_state(const char* library = FAKE_FORCEDIMENSION_LIBRARY) {
  void* handle = dlopen(library, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) return {};
  auto get_status = reinterpret_cast<int (*)(int*, char)>(dlsym(handle, "dhdGetStatus"));
  int status[32] = {};
  get_status(status, 0);
  dlclose(handle);
  return {status[5], status[6], status[14]};  // DHD_STATUS_FORCE, _BRAKE, _FORCEOFFCAUSE
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

// Issue 38: the device's velocity guard turns forces off while dhdSetForce goes on succeeding.
// The driver sees it at the next read (dhdGetStatus), reports a device fault naming the cause in
// the SDK's words, and once the hand is slow turns forces on again, commanding zero at once.
TEST(ForceDimension, ForcesTheDeviceTurnsOffAreAFaultNamingTheCauseAndComeBackZeroFirst) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("velocity 0 0.5"), 0);
  DeviceReading reading;
  DeviceCommand push;
  push.tau[0] = 12.0;
  int cut_at = -1, seen_at = -1;
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk) << "tick " << k;
    if (reading.safe_state) {
      seen_at = k;
      break;
    }
    ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk) << "tick " << k;  // the setter succeeds
    if (cut_at < 0 && force_state().force == 0) cut_at = k;
  }
  ASSERT_GE(cut_at, 0) << "the stand-in's guard never tripped";
  EXPECT_EQ(force_state().cause, 2);  // DHD_FORCE_OFF_VELOCITY (SOURCES.md §1.5)
  EXPECT_EQ(seen_at, cut_at + 1) << "the cut at tick " << cut_at << " was not seen at the next read";
  EXPECT_NE(device.fault_reason().find("velocity guard"), std::string::npos) << device.fault_reason();
  EXPECT_NE(device.fault_reason().find("DHD_FORCE_OFF_VELOCITY"), std::string::npos) << device.fault_reason();
  // As the loop does on a faulted tick: the safe state, a zero command; until the hand is slow
  // (the brake slows it) every reading says safe_state.
  standin.clear();
  int waited = 0;
  for (;; ++waited) {
    ASSERT_LT(waited, 200) << "forces never came back";
    device.enter_safe_state();
    ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    if (!reading.safe_state) break;
  }
  EXPECT_GT(waited, 0);
  EXPECT_LT(std::fabs(reading.q_dot[0]), 0.1);  // resume_speed's default
  EXPECT_EQ(line_after(standin.calls(), "dhdEnableForce 1 0").rfind("dhdSetForce 0 0 0 0", 0), 0u)
      << standin.calls();
  EXPECT_EQ(force_state().force, 1);
  push.tau[0] = 1.0;
  const double x0 = reading.q[0];
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    ASSERT_FALSE(reading.safe_state);
  }
  EXPECT_GT(reading.q[0], x0 + 1e-3);  // forces act again
  device.stop();
}

// A person's force-off (the force button) is a fault too, and theirs to end: the driver does not
// turn forces on itself, and goes on once the button turns them on, with a zero command first.
TEST(ForceDimension, ForcesAPersonTurnsOffStayOffUntilTheyTurnThemOn) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("forcebutton 0"), 0);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_TRUE(reading.safe_state);
  EXPECT_NE(device.fault_reason().find("DHD_FORCE_OFF_BUTTON"), std::string::npos) << device.fault_reason();
  standin.clear();
  for (int k = 0; k < 20; ++k) {
    device.enter_safe_state();
    ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_TRUE(reading.safe_state) << "tick " << k;
  }
  EXPECT_EQ(standin.calls().find("dhdEnableForce 1"), std::string::npos) << standin.calls();
  ASSERT_EQ(standin.control("forcebutton 0"), 0);  // pressed again: forces on
  standin.clear();
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_FALSE(reading.safe_state);
  EXPECT_EQ(line_after(standin.calls(), "dhdGetStatus 0").rfind("dhdSetForce 0 0 0 0", 0), 0u) << standin.calls();
  device.stop();
}

// Issue 38: gravity compensation goes out with force commands only (SOURCES.md §1.6), so forces
// enabled with no command let the arm fall until the loop's first write. The driver commands zero
// as soon as they are enabled: 7.5 ms later the arm has not moved.
TEST(ForceDimension, ForcesAreCommandedZeroAsSoonAsTheyAreEnabled) {
  for (const char* model : {"omega.3", "falcon"}) {
    SCOPED_TRACE(model);
    Standin standin(model);
    DriverDevice device(fd());
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    EXPECT_EQ(line_after(standin.calls(), "dhdEnableForce 1 0").rfind("dhdSetForce 0 0 0 0", 0), 0u)
        << standin.calls();
    ASSERT_EQ(standin.control("dt 0.0005"), 0);
    ASSERT_EQ(standin.control("elapse 0 0.0075"), 0);  // before the loop's first tick
    DeviceReading reading;
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_EQ(reading.q_dot[2], 0.0) << "falling";
    EXPECT_EQ(reading.q[2], 0.0);
    device.stop();
  }
}

// Issue 38: dhdSetBrakes does not take a device out of FORCE mode (SOURCES.md §1.6): the safe
// state turns forces off. A write after it is taken (OK) but applies nothing; the next read with the
// hand slow turns forces on again, zero first: the device leaves its safe state its own way, as
// driver.h allows, and the writes from then on apply (the next test).
TEST(ForceDimension, TheSafeStateTurnsForcesOffAndTheNextSlowReadTurnsThemOnZeroFirst) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  device.enter_safe_state();
  ForceState state = force_state();
  EXPECT_EQ(state.force, 0);
  EXPECT_EQ(state.brake, 1);
  DeviceCommand push;
  push.tau[0] = 5.0;
  ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
  EXPECT_EQ(force_state().force, 0);
  standin.clear();
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_FALSE(reading.safe_state);
  EXPECT_EQ(reading.q[0], 0.0);  // the push after the safe state applied nothing
  EXPECT_EQ(line_after(standin.calls(), "dhdEnableForce 1 0").rfind("dhdSetForce 0 0 0 0", 0), 0u)
      << standin.calls();
  EXPECT_EQ(force_state().force, 1);
  device.stop();
}

// Issue 43: dhdSetForce's own failure (nothing else failing) is a write error naming the call and
// the SDK's error; after the loop's safe state, forces come back at the next read, zero first.
TEST(ForceDimension, AFailedSetForceIsAWriteErrorNamingItAndForcesComeBack) {
  Standin standin("omega.3");
  DriverDevice device(fd());
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(standin.control("fail 0 dhdSetForce"), 0);
  DeviceCommand push;
  push.tau[0] = 1.0;
  EXPECT_EQ(device.write(push, kT), DeviceStatus::kError);
  const std::string why = device.fault_reason();
  EXPECT_EQ(why.rfind("dhdSetForce: ", 0), 0u) << why;
  EXPECT_NE(why.find("(DHD error 2)"), std::string::npos) << why;
  device.enter_safe_state();  // as the loop does after a failed write
  EXPECT_EQ(force_state().force, 0);
  ASSERT_EQ(standin.control("fail 0 none"), 0);
  standin.clear();
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_FALSE(reading.safe_state);
  EXPECT_EQ(line_after(standin.calls(), "dhdEnableForce 1 0").rfind("dhdSetForce 0 0 0 0", 0), 0u)
      << standin.calls();
  const double x0 = reading.q[0];
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  }
  EXPECT_GT(reading.q[0], x0 + 1e-3);
  device.stop();
}

// A left-handed device (dhdIsLeftHanded) reports its gripper angle negative (SOURCES.md §1.6): the
// driver mirrors it, and the gripper force, so hapticd sees a right-handed gripper.
TEST(ForceDimension, ALeftHandedGripperComesThroughAsARightHandedOne) {
  Standin standin("omega.7-left");
  void* library = dlopen(FORCEDIMENSION_DRIVER, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(library, nullptr) << dlerror();
  const auto* api = reinterpret_cast<haptic_driver_entry_fn>(dlsym(library, HAPTIC_DRIVER_ENTRY_SYMBOL))();
  char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
  void* driver = api->create(params().c_str(), error);
  ASSERT_NE(driver, nullptr) << error;
  ASSERT_EQ(api->start(driver), HAPTIC_DRIVER_OK);
  haptic_driver_reading reading{};
  ASSERT_EQ(api->read(driver, &reading), HAPTIC_DRIVER_OK);
  EXPECT_EQ(reading.gripper, 0.5);  // open, as on a right-handed omega.7
  haptic_driver_command command{};
  command.gripper_force = 2.0;
  standin.clear();
  ASSERT_EQ(api->write(driver, &command, kT), HAPTIC_DRIVER_OK);
  EXPECT_TRUE(in_order(standin.calls(), {"dhdSetForceAndTorqueAndGripperForce 0 0 0 0 0 0 -2 0"}));
  api->stop(driver);
  api->destroy(driver);
  dlclose(library);
}

// The Falcon is not a device the DRD supports (drdIsSupported): it is never auto-initialized; one
// in RESET mode is refused saying to calibrate it by hand.
TEST(ForceDimension, AFalconIsNeverAutoInitialized) {
  Standin standin("falcon");
  {
    DriverDevice device(fd());
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    device.stop();
  }
  EXPECT_TRUE(in_order(standin.calls(), {"drdIsSupported 0", "dhdEnableForce 1 0"}));
  ASSERT_EQ(standin.control("uncalibrate 0"), 0);
  standin.clear();
  DriverDevice device(fd());
  EXPECT_EQ(device.start(), DeviceStatus::kError);
  EXPECT_NE(device.fault_reason().find("drdIsSupported: false"), std::string::npos) << device.fault_reason();
  EXPECT_NE(device.fault_reason().find("calibrate it by hand"), std::string::npos) << device.fault_reason();
  EXPECT_EQ(standin.calls().find("drdAutoInit"), std::string::npos) << standin.calls();
}

// A runtime without the wrist and gripper functions drives a wrist-less device (the kit passes);
// a device with a wrist is refused there, naming what is missing.
TEST(ForceDimension, WristFunctionsAreOptionalWhereTheDeviceHasNoWrist) {
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  test::StandinLibrary standin(FAKE_FORCEDIMENSION_NOWRIST_LIBRARY, "fake_dhd");
  const std::string nowrist = std::string(R"({"library": ")") + FAKE_FORCEDIMENSION_NOWRIST_LIBRARY + "\"}";
  std::ostringstream log;
  for (const auto& result : driver_kit::run_kit({FORCEDIMENSION_DRIVER, nowrist, true, test::kTestCallTimeoutS}, log)) {
    EXPECT_TRUE(result.passed) << result.name << ": " << result.detail << "\n" << log.str();
  }
  setenv("FAKE_DHD_DEVICES", "omega.7", 1);
  ASSERT_EQ(standin.control("reset"), 0);
  const std::string why = refusal(test::driver_options(FORCEDIMENSION_DRIVER, nowrist));
  EXPECT_NE(why.find("lacks dhdGetOrientationFrame"), std::string::npos) << why;
}

// DHD_MOTOR_SATURATED (SOURCES.md §1.4): the device scaled a command down. The ABI has no field
// for it, so the driver counts such commands and says how many at stop.
TEST(ForceDimension, SaturatedCommandsAreCountedAndLoggedAtStop) {
  Standin standin("omega.3");
  ASSERT_EQ(standin.control("saturate 0 on"), 0);
  void* library = dlopen(FORCEDIMENSION_DRIVER, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(library, nullptr) << dlerror();
  const auto* api = reinterpret_cast<haptic_driver_entry_fn>(dlsym(library, HAPTIC_DRIVER_ENTRY_SYMBOL))();
  char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
  void* driver = api->create(params().c_str(), error);
  ASSERT_NE(driver, nullptr) << error;
  std::vector<std::string> warnings;
  api->set_log(
      driver,
      [](void* context, int level, const char* message) {
        if (level == HAPTIC_DRIVER_LOG_WARNING) static_cast<std::vector<std::string>*>(context)->push_back(message);
      },
      &warnings);
  ASSERT_EQ(api->start(driver), HAPTIC_DRIVER_OK);
  haptic_driver_command command{};
  command.tau[0] = 1.0;
  for (int k = 0; k < 10; ++k) ASSERT_EQ(api->write(driver, &command, kT), HAPTIC_DRIVER_OK);
  api->stop(driver);
  bool said = false;
  for (const std::string& warning : warnings) {
    said = said || warning.rfind("10 of 10 force commands came back DHD_MOTOR_SATURATED", 0) == 0;
  }
  EXPECT_TRUE(said) << (warnings.empty() ? std::string("no warning") : warnings.back());
  api->destroy(driver);
  dlclose(library);
}

}  // namespace
}  // namespace haptic::runtime
