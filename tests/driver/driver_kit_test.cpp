// The driver test kit (tools/driver_kit, the program haptic-driver-kit) and hapticd's handling of a
// driver's faults. DriverKit.* runs the kit's checks against the example driver
// (driver/example/point_mass_driver.c), where all pass, and against drivers that break what hapticd
// needs, where the right check fails saying why; it also tests the example's own physics.
// DriverFaults.* checks hapticd's side with the example's injected faults: NaN readings, stale
// readings, a read that hangs, an ABI mismatch, a library that is not a driver.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "driver_kit.hpp"
#include "driver_test_support.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

DriverOptions example(const std::string& params) { return test::driver_options(POINT_MASS_DRIVER, params); }

using test::refusal;

std::vector<driver_kit::CheckResult> kit(const std::string& library, const std::string& params = "{}") {
  std::ostringstream log;
  return driver_kit::run_kit({library, params, true, test::kTestCallTimeoutS}, log);
}

// ---- What any driver owes hapticd: the kit ----

TEST(DriverKit, TheExampleDriverPassesEveryCheck) {
  const auto results = kit(POINT_MASS_DRIVER);
  ASSERT_EQ(results.size(), 4u);
  for (const auto& result : results) EXPECT_TRUE(result.passed) << result.name << ": " << result.detail;
}

// The example driver took any key in params and let a wrongly typed value say only "cannot parse";
// the vendor drivers refused both. Now the kit checks every driver for it, and the example passes.
TEST(DriverKit, UnknownParamsAndValuesOfTheWrongKindAreRefusedNamingThem) {
  const auto results = kit(POINT_MASS_DRIVER, R"({"mass": 0.05, "initial": [0, 0, 0.01], "fault": "none"})");
  ASSERT_EQ(results.size(), 4u);
  EXPECT_TRUE(results[3].passed) << results[3].detail;
  const auto refusal = [](const std::string& params) {
    try {
      runtime::DriverOptions options;
      options.library = POINT_MASS_DRIVER;
      options.params_json = params;
      runtime::DriverDevice device(options);
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string("(taken)");
  };
  EXPECT_NE(refusal(R"({"dampnig": 0.5})").find("params.dampnig: not an option of this driver (it takes mass, damping"),
            std::string::npos) << refusal(R"({"dampnig": 0.5})");
  EXPECT_NE(refusal(R"({"mass": "heavy"})").find("params.mass: expected a number"), std::string::npos)
      << refusal(R"({"mass": "heavy"})");
  EXPECT_NE(refusal(R"({"push": 1})").find("params.push: expected [x, y, z] (three numbers)"), std::string::npos)
      << refusal(R"({"push": 1})");
  EXPECT_NE(refusal(R"({"fault": 3})").find("params.fault: expected a string"), std::string::npos)
      << refusal(R"({"fault": 3})");
  EXPECT_EQ(refusal(R"({"mass": 0.02, "push": [0, 0, -1], "fault": "none"})"), "(taken)");
}

TEST(DriverKit, ADriverReadingNaNFailsTheReadingsCheckSayingWhere) {
  const auto results = kit(POINT_MASS_DRIVER, R"({"fault": "nan", "fault_after": 50})");
  EXPECT_TRUE(results[0].passed) << results[0].detail;
  EXPECT_FALSE(results[1].passed);
  EXPECT_NE(results[1].detail.find("at tick 50"), std::string::npos) << results[1].detail;
}

TEST(DriverKit, ADriverWhoseSequenceStopsFailsAsStale) {
  const auto results = kit(POINT_MASS_DRIVER, R"({"fault": "stale", "fault_after": 10})");
  EXPECT_FALSE(results[1].passed);
  EXPECT_NE(results[1].detail.find("stale"), std::string::npos) << results[1].detail;
}

// driver.h: a write after enter_safe_state is taken (the device may stay safe): one that fails
// it fails the readings check, saying so.
TEST(DriverKit, ADriverThatFailsAWriteAfterTheSafeStateFailsSayingWhy) {
  const auto results = kit(POINT_MASS_DRIVER, R"({"fault": "fail_when_safe"})");
  EXPECT_TRUE(results[0].passed) << results[0].detail;
  EXPECT_FALSE(results[1].passed);
  EXPECT_NE(results[1].detail.find("right after enter_safe_state()"), std::string::npos) << results[1].detail;
}

TEST(DriverKit, ADriverThatPushesTheWrongWayFailsTheAxesCheck) {
  // A push of its own along -x beats the kit's 5 % of max_force along +x: the tool moves the
  // wrong way, as with a negated axis.
  const auto results = kit(POINT_MASS_DRIVER, R"({"push": [-5, 0, 0], "max_force": 10})");
  EXPECT_FALSE(results[2].passed);
  EXPECT_NE(results[2].detail.find("not along +x"), std::string::npos) << results[2].detail;
}

TEST(DriverKit, ALibraryBuiltForAnotherAbiFailsToLoadNamingBothVersions) {
  const auto results = kit(WRONG_ABI_DRIVER);
  EXPECT_FALSE(results[0].passed);
  EXPECT_NE(results[0].detail.find("ABI"), std::string::npos) << results[0].detail;
}

// ---- The example driver's physics: units ----

TEST(DriverKit, TheExampleIsTheExactPointMass) {
  // 2 N on a 0.5 kg, 1 N·s/m mass from rest for 0.2 s: x = (F/b)(t − (m/b)(1 − e^(−b t/m))).
  DriverDevice device(example(R"({"mass": 0.5, "damping": 1.0, "initial": [0.01, 0, 0]})"));
  CartesianModel model;
  DevicePort port(device, model);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ToolReading reading;
  for (int k = 0; k < 200; ++k) ASSERT_EQ(port.write(ToolCommand{{2.0, 0.0, 0.0}}, kT), DeviceStatus::kOk);
  ASSERT_EQ(port.read(reading), DeviceStatus::kOk);
  const double m = 0.5, b = 1.0, F = 2.0, t = 0.2;
  EXPECT_NEAR(reading.p_WT.x, 0.01 + F / b * (t - m / b * -std::expm1(-b * t / m)), 1e-12);
  EXPECT_NEAR(reading.v_WT.x, F / b * -std::expm1(-b * t / m), 1e-12);
}

TEST(DriverKit, ButtonsComeThroughMaskedToTheDeclaredCount) {
  DriverDevice device(example(R"({"button_period_s": 0.01})"));
  ASSERT_EQ(device.description().buttons, 1u);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  int pressed = 0, released = 0;
  for (int k = 0; k < 40; ++k) {
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    EXPECT_EQ(reading.buttons & ~1u, 0u);
    (reading.buttons & 1u ? pressed : released)++;
    ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  }
  EXPECT_EQ(pressed, 20);  // 10 ms pressed, 10 ms released, twice
  EXPECT_EQ(released, 20);
}

// ---- hapticd's side: faults ----

TEST(DriverFaults, ANaNReadingIsADeviceFaultAndNeverReachesTheModel) {
  DriverDevice device(example(R"({"fault": "nan", "fault_after": 5})"));
  CartesianModel model;
  DevicePort port(device, model);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ToolReading reading;
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(port.read(reading), DeviceStatus::kOk) << k;
    ASSERT_EQ(port.write(ToolCommand{}, kT), DeviceStatus::kOk);
  }
  EXPECT_EQ(port.read(reading), DeviceStatus::kError);
  EXPECT_TRUE(std::isfinite(port.tool().p_WT.z));  // the last good state, not the NaN
}

TEST(DriverFaults, AReadingThatStopsChangingIsStaleAfterTheConfiguredTicks) {
  DriverOptions options = example(R"({"fault": "stale", "fault_after": 10})");
  options.stale_after = 3;
  DriverDevice device(options);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  int first_error = -1;
  for (int k = 0; k < 30 && first_error < 0; ++k) {
    if (device.read(reading) != DeviceStatus::kOk) first_error = k;
    device.write(DeviceCommand{}, kT);
  }
  // Ticks 0..9 sample; from tick 10 the sequence stands still: 10, 11, 12 repeat it 3 times.
  EXPECT_EQ(first_error, 12);
  EXPECT_EQ(device.stale_readings(), 1u);
}

TEST(DriverFaults, AReadThatHangsTimesOutGoesSafeAndStaysFaulted) {
  DriverOptions options = example(R"({"fault": "hang", "fault_after": 3})");
  options.call_timeout_s = 0.5;  // a true hang: the driver never answers
  auto device = std::make_unique<DriverDevice>(options);
  ASSERT_EQ(device->start(), DeviceStatus::kOk);
  DeviceReading reading;
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(device->read(reading), DeviceStatus::kOk);
    ASSERT_EQ(device->write(DeviceCommand{}, kT), DeviceStatus::kOk);
  }
  const auto before = std::chrono::steady_clock::now();
  EXPECT_EQ(device->read(reading), DeviceStatus::kError);  // the driver never answers
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
  EXPECT_TRUE(device->hung());
  EXPECT_GE(waited, 0.5);
  EXPECT_LT(waited, 5.0);  // bounded: the loop goes on (generous: a loaded machine)
  // Faulted for good: later calls are errors at once, without waiting on the driver again.
  EXPECT_EQ(device->write(DeviceCommand{}, kT), DeviceStatus::kError);
  EXPECT_EQ(device->read(reading), DeviceStatus::kError);
  EXPECT_TRUE(device->driver_thread_running());
  device->stop();  // the example's stop() releases the hung read, so its thread can be joined
  EXPECT_FALSE(device->driver_thread_running());
  device.reset();
}

TEST(DriverFaults, AnAbiMismatchIsRefusedNamingBothVersions) {
  DriverOptions options;
  options.library = WRONG_ABI_DRIVER;
  const std::string message = refusal(options);
  EXPECT_NE(message.find(WRONG_ABI_DRIVER), std::string::npos) << message;
  EXPECT_NE(message.find("ABI version 3"), std::string::npos) << message;
  EXPECT_NE(message.find("speaks versions 1 to 2"), std::string::npos) << message;
}

TEST(DriverFaults, WhatIsNotADriverIsRefusedNamingWhy) {
  DriverOptions missing;
  missing.library = "/nonexistent/libnothing.so";
  EXPECT_NE(refusal(missing).find("cannot load"), std::string::npos) << refusal(missing);
  DriverOptions not_a_driver;
  not_a_driver.library = "libm.so.6";
  EXPECT_NE(refusal(not_a_driver).find("exports no haptic_driver_entry()"), std::string::npos)
      << refusal(not_a_driver);
  EXPECT_NE(refusal(example(R"({"mass": -1})")).find("create() refused: params.mass must be > 0"),
            std::string::npos)
      << refusal(example(R"({"mass": -1})"));
  EXPECT_NE(refusal(example(R"({"fault": "sometimes"})")).find("params.fault"), std::string::npos);
  DriverOptions clocked = example("{}");
  clocked.device_clocked = true;  // the example's servo rate is 0 unless asked for
  EXPECT_NE(refusal(clocked).find("servo_rate_hz must be 100 ... 10000 Hz"), std::string::npos)
      << refusal(clocked);
}

TEST(DriverFaults, AStartThatFailsIsAnError) {
  DriverDevice device(example(R"({"fault": "fail_start"})"));
  EXPECT_EQ(device.start(), DeviceStatus::kError);
}

// ---- Both ABI versions ----

// A driver built against the version 1 header (the example's source, frozen header) still loads,
// runs, and passes the kit; what version 2 adds is absent: no mass-damper, so no stability report
// or passivity on its port.
TEST(DriverAbi, AVersion1DriverStillLoadsRunsAndPassesTheKit) {
  DriverOptions options;
  options.library = POINT_MASS_DRIVER_ABI1;
  options.params_json = R"({"mass": 0.05, "damping": 0.5, "turn_rate": 1.0})";
  DriverDevice device(options);
  EXPECT_EQ(device.abi_version(), 1u);
  EXPECT_EQ(device.description().apparent_mass, 0.0);
  EXPECT_EQ(device.description().apparent_damping, 0.0);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  for (int k = 0; k < 10; ++k) {
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    DeviceCommand command;
    command.tau[0] = 0.1;
    ASSERT_EQ(device.write(command, kT), DeviceStatus::kOk);
  }
  EXPECT_GT(reading.q[0], 0.0);  // pushed along +x
  device.stop();
  for (const auto& result : kit(POINT_MASS_DRIVER_ABI1)) {
    EXPECT_TRUE(result.passed) << result.name << ": " << result.detail;
  }
}

// A version 2 driver gives the port its mass-damper (the weakest axis), which turns on what needs
// a device model, and its messages reach hapticd's log.
TEST(DriverAbi, AVersion2DriverGivesItsMassDamperAndSpeaksInTheLog) {
  DriverOptions options = example(R"({"mass": 0.05, "damping": 0.5})");
  std::vector<std::string> said;
  options.log = [&said](int level, const std::string& message) {
    said.push_back(std::to_string(level) + " " + message);
  };
  DriverDevice device(options);
  EXPECT_EQ(device.abi_version(), 2u);
  EXPECT_EQ(device.description().apparent_mass, 0.05);
  EXPECT_EQ(device.description().apparent_damping, 0.5);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  device.stop();
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0], "0 started: 0.05 kg, 0.5 N*s/m per axis");
}

// A profile measured on the bench (haptic-lab identify --profile-out) takes the place of what the
// driver reports: the weakest axis's mass and damping, and the delay the stability report counts.
TEST(DriverAbi, AMeasuredProfileTakesThePlaceOfTheDriversFigures) {
  DriverOptions options = example(R"({"mass": 0.05, "damping": 0.5})");
  options.profile = DriverOptions::Profile{{0.12, 0.09, 0.11}, {2.0, 3.0, 1.5}, 0.0025};
  DriverDevice device(options);
  EXPECT_EQ(device.description().apparent_mass, 0.09);
  EXPECT_EQ(device.description().apparent_damping, 1.5);
  EXPECT_EQ(device.description().delay_s, 0.0025);
  // Without one, the driver's own, and no delay known.
  DriverDevice plain(example(R"({"mass": 0.05, "damping": 0.5})"));
  EXPECT_EQ(plain.description().apparent_mass, 0.05);
  EXPECT_EQ(plain.description().delay_s, 0.0);
}

// What version 2 adds is checked like the rest (a negative or NaN mass is refused naming the
// fields), and a port whose axes differ is modelled by its weakest.
TEST(DriverAbi, Version2FieldsAreCheckedAndTheWeakestAxisModelsThePort) {
  for (const char* bad : {R"({"reported_mass": [0.05, -1, 0.05]})", R"({"reported_mass": [0.05, nan, 0.05]})"}) {
    const std::string message = refusal(example(bad));
    EXPECT_NE(message.find("describe(): apparent_mass and apparent_damping must be finite and >= 0"),
              std::string::npos)
        << bad << ": " << message;
  }
  DriverDevice uneven(example(R"({"damping": 0.3, "reported_mass": [0.05, 0.02, 0.08]})"));
  EXPECT_EQ(uneven.description().apparent_mass, 0.02);
  EXPECT_EQ(uneven.description().apparent_damping, 0.3);
  // One axis unknown (0): the whole model is unknown, as for a version 1 driver.
  DriverDevice partial(example(R"({"reported_mass": [0.05, 0, 0.05]})"));
  EXPECT_EQ(partial.description().apparent_mass, 0.0);
}

// A driver named without a folder is found among hapticd's drivers (here: the build tree's, since
// this test runs from it), so a configuration can say "point_mass_driver.so" wherever it is
// installed; a path, or a name found nowhere, is left to dlopen.
TEST(DriverAbi, ABareNameIsFoundInTheDriverFolders) {
  const std::string found = resolve_driver_library("point_mass_driver.so");
  EXPECT_EQ(std::filesystem::canonical(found), std::filesystem::canonical(POINT_MASS_DRIVER)) << found;
  EXPECT_EQ(resolve_driver_library("/x/y.so"), "/x/y.so");
  EXPECT_EQ(resolve_driver_library("libnowhere.so"), "libnowhere.so");
  DriverOptions options;
  options.library = "point_mass_driver.so";
  DriverDevice device(options);
  EXPECT_EQ(device.abi_version(), 2u);
}

}  // namespace
}  // namespace haptic::runtime
