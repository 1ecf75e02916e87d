// A device behind a driver library running hapticd end to end: the example driver
// (driver/example/point_mass_driver.c, a plugin built against <haptic/driver.h> alone) loaded from
// the configuration, in lockstep, driven through the SDK; and its faults as every client sees them.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

/// A lockstep configuration whose port 0 is the example driver with `params` (JSON object body).
/// The driver-call deadline is 5 s unless `driver_extra` sets one: a loaded machine may leave the
/// driver thread unscheduled past the 20 ms default, and what these tests check does not depend
/// on the call's speed (docs/devices.md, "What the timeout means on a loaded host").
std::string driver_config(const std::string& params, const std::string& driver_extra = {}) {
  const bool sets_timeout = driver_extra.find("call_timeout_ms") != std::string::npos;
  return R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
             "real_time": {"use_fifo": false},
             "driver": {"library": ")" POINT_MASS_DRIVER R"(", "params": {)" + params + "}" +
         (sets_timeout ? "" : R"(, "call_timeout_ms": 5000)") +
         (driver_extra.empty() ? "" : ", " + driver_extra) + "}}";
}

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

TEST(DriverDevice, APluginRunsHapticdEndToEndAndRestsOnAWall) {
  // The driver's own push (−1 N along z) stands in for the operator; the wall 10 mm below the
  // tool (500 N/m) must carry it: at rest the force is 1 N and the penetration 1/500 m.
  test::ServerProcess server(driver_config(R"("initial": [0, 0, 0.01], "push": [0, 0, -1],
                                              "mass": 0.05, "damping": 0.5)"));
  Client client(config_for(server));
  const DeviceInfo& info = client.device_info();
  EXPECT_EQ(info.model, "driver");
  EXPECT_FALSE(info.simulated);
  EXPECT_NE(info.name.find("point mass driver"), std::string::npos) << info.name;
  EXPECT_EQ(info.dof, 3u);
  EXPECT_EQ(info.max_force, 10.0);
  State s = step_and_get(client, 1);
  EXPECT_NEAR(s.position.z, 0.01, 1e-12);  // the driver's initial pose, through the Cartesian model
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {500.0, 2.0}});
  s = step_and_get(client, 3000);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_NEAR(s.force.z, 1.0, 1e-3);
  EXPECT_NEAR(s.position.z, -1.0 / 500.0, 1e-5);
  // There is no simulated operator behind a driver: SetOperator says so.
  try {
    client.set_operator(OperatorInput::push({0, 0, -2.0}));
    ADD_FAILURE() << "SetOperator was accepted on a driver's port";
  } catch (const Error& error) {
    EXPECT_EQ(error.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(error.what()).find("not simulated"), std::string::npos) << error.what();
  }
}

// An ABI version 2 driver gives its port a mass-damper, so a wall there gets the same stability
// report as on a simulated device: known, with its largest stable stiffness, and a wall beyond it
// is flagged with a warning.
TEST(DriverDevice, AVersion2DriverPortGetsAStabilityReportFromItsMassDamper) {
  test::ServerProcess server(driver_config(R"("mass": 0.05, "damping": 0.5)"));
  Client client(config_for(server));
  auto soft = client.add_wall({.point = {0, 0, -0.05}, .normal = {0, 0, 1}, .impedance = {500.0, 2.0}});
  const StabilityReport& report = soft.stability();
  EXPECT_TRUE(report.device_known);
  EXPECT_EQ(report.device_mass, 0.05);
  EXPECT_EQ(report.device_damping, 0.5);
  EXPECT_TRUE(report.stable);
  EXPECT_GT(report.max_stable_stiffness, 500.0);
  auto stiff = client.add_wall({.point = {0, 0, -0.06}, .normal = {0, 0, 1},
                                .impedance = {50.0 * report.max_stable_stiffness, 0.0}});
  EXPECT_TRUE(stiff.stability().device_known);
  EXPECT_FALSE(stiff.stability().stable);
  EXPECT_FALSE(stiff.stability().warning.empty());
}

// A driver port configured with a profile measured on the bench (docs/identification.md) reports
// the profile's mass-damper, and its delay, and its actuator's lag, lower the largest stable
// stiffness the report gives.
TEST(DriverDevice, AMeasuredProfilesFiguresAndDelayAreWhatTheStabilityReportUses) {
  const auto limit = [](double delay_s, double* mass = nullptr, double* damping = nullptr, double lag_s = 0.0) {
    test::ServerProcess server(driver_config(R"("mass": 0.05, "damping": 0.5)",
                                             R"("profile": {"apparent_mass": {"x": 0.08, "y": 0.07, "z": 0.09},
                                                            "apparent_damping": {"x": 0.6, "y": 0.6, "z": 0.6},
                                                            "actuator_lag_s": )" + std::to_string(lag_s) + R"(,
                                                            "delay_s": )" + std::to_string(delay_s) + "}"));
    Client client(config_for(server));
    const StabilityReport report =
        client.add_wall({.point = {0, 0, -0.05}, .normal = {0, 0, 1}, .impedance = {500.0, 2.0}}).stability();
    if (mass != nullptr) *mass = report.device_mass;
    if (damping != nullptr) *damping = report.device_damping;
    return report.max_stable_stiffness;
  };
  double mass = 0.0, damping = 0.0;
  const double undelayed = limit(0.0, &mass, &damping);
  EXPECT_EQ(mass, 0.07);  // the profile's weakest axis, not the driver's 0.05
  EXPECT_EQ(damping, 0.6);
  const double delayed = limit(0.002);
  EXPECT_LT(delayed, 0.8 * undelayed) << "two ticks of delay must lower the limit";
  const double lagged = limit(0.0, nullptr, nullptr, 0.005);
  EXPECT_LT(lagged, 0.5 * undelayed) << "5 ms of an amplifier's lag must lower it too";
  std::printf("  the largest stable stiffness: %.0f N/m without delay, %.0f N/m with 2 ms, %.0f N/m behind 5 ms of lag\n",
              undelayed, delayed, lagged);
}

// A Force Dimension device through its vendor's runtime (the driver in driver/vendors against the
// stand-in of libdrd, tests/driver/standins), the whole server around it in lockstep: the
// stand-in's 1 N hand rests on a 500 N/m wall 2 mm deep; unplugged the device faults (zero force,
// the event naming the vendor's error), and once plugged in again it is driven again without a
// restart.
TEST(DriverDevice, AForceDimensionDeviceRestsOnAWallFaultsWhenUnpluggedAndComesBack) {
  setenv("FAKE_DHD_DEVICES", "omega.3", 1);
  setenv("FAKE_DHD_SCRIPT", "0 hand 0 0 0 -1;2000 unplug 0;2100 replug 0", 1);
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "driver": {"library": ")" FORCEDIMENSION_DRIVER R"(", "call_timeout_ms": 5000,
                 "params": {"library": ")" FAKE_FORCEDIMENSION_LIBRARY R"("}}})");
  unsetenv("FAKE_DHD_SCRIPT");
  Client client(config_for(server));
  EXPECT_NE(client.device_info().name.find("Force Dimension omega.3"), std::string::npos)
      << client.device_info().name;
  std::mutex mutex;
  std::string fault_message;
  client.on_event([&](const Event& event) {
    std::lock_guard lock(mutex);
    if (event.kind == Event::Kind::kDeviceFault && fault_message.empty()) fault_message = event.message;
  });
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {500.0, 5.0}});
  State s = step_and_get(client, 1990);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.position.z, -1.0 / 500.0, 2e-5);
  EXPECT_NEAR(s.force.z, 1.0, 1e-2);
  // The script counts the runtime's force calls, not ticks: step until the fault shows, then
  // until it clears (each bounded).
  int steps = 0;
  do {
    s = step_and_get(client, 10);
  } while ((s.flags & kDeviceFault) == 0 && ++steps < 300);
  ASSERT_NE(s.flags & kDeviceFault, 0u) << "no fault within 3000 ticks of the unplug";
  EXPECT_EQ(s.force, (Vec3{0, 0, 0}));
  steps = 0;
  do {
    s = step_and_get(client, 10);
  } while ((s.flags & kDeviceFault) != 0 && ++steps < 300);
  ASSERT_EQ(s.flags & kDeviceFault, 0u) << "still faulted 3000 ticks after the replug";
  s = step_and_get(client, 2000);  // driven again, without a restart: back on the wall
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_NEAR(s.position.z, -1.0 / 500.0, 2e-5);
  EXPECT_NEAR(s.force.z, 1.0, 1e-2);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (;;) {
    {
      std::lock_guard lock(mutex);
      if (!fault_message.empty() || std::chrono::steady_clock::now() > deadline) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::lock_guard lock(mutex);
  // The runtime's own words for the call that met the unplugged device (DHD_ERROR_COM).
  EXPECT_NE(fault_message.find("(device 0: dhd"), std::string::npos) << fault_message;
  EXPECT_NE(fault_message.find("(DHD error 2)"), std::string::npos) << fault_message;
}

TEST(DriverDevice, ANaNFromTheDriverIsADeviceFaultWithZeroForceAndTheLastGoodState) {
  test::ServerProcess server(driver_config(R"("initial": [0, 0, -0.001], "push": [0, 0, -1],
                                              "fault": "nan", "fault_after": 100)"));
  Client client(config_for(server));
  std::mutex mutex;
  std::condition_variable arrived;
  std::string fault_message;
  client.on_event([&](const Event& event) {
    if (event.kind != Event::Kind::kDeviceFault) return;
    std::lock_guard lock(mutex);
    fault_message = event.message;
    arrived.notify_all();
  });
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {500.0, 2.0}});
  State s = step_and_get(client, 50);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_GT(s.force.z, 0.0);
  s = step_and_get(client, 100);
  EXPECT_NE(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.force, (Vec3{0, 0, 0}));
  EXPECT_TRUE(finite(s.position));
  EXPECT_GE(client.stats().device_faults, 49u);
  // The event says why in the driver's own words (ABI 2's last_error).
  std::unique_lock lock(mutex);
  ASSERT_TRUE(arrived.wait_for(lock, std::chrono::seconds(5), [&] { return !fault_message.empty(); }));
  EXPECT_NE(fault_message.find("(device 0: the example's injected fault: a NaN reading)"), std::string::npos)
      << fault_message;
}

TEST(DriverDevice, ADriverThatHangsTimesOutTheLoopGoesOnSafeAndTheServerStopsCleanly) {
  test::ServerProcess server(driver_config(R"("initial": [0, 0, -0.001], "fault": "hang",
                                              "fault_after": 100)",
                                           R"("call_timeout_ms": 1000)"));
  Client client(config_for(server));
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {500.0, 2.0}});
  State s = step_and_get(client, 100);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  // Tick 101's read never returns: the loop waits the second, faults the device for good and goes
  // on; the steps after it do not wait on the driver again.
  s = step_and_get(client, 200);
  EXPECT_NE(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.force, (Vec3{0, 0, 0}));
  EXPECT_TRUE(finite(s.position));
  EXPECT_EQ(client.stats().ticks, 300u);
  // The server still serves, and it stops cleanly (checked by ServerProcess's destructor: the
  // driver's stop() releases its hung read).
  auto sphere = client.add_sphere({.center = {0, 0.05, 0}, .radius = 0.01, .impedance = {200.0, 1.0}});
}

TEST(DriverDevice, ButtonsAndOrientationReachTheStepReplyAndTheUdpStream) {
  // The example's button 0 is pressed during every other 10 ms, and its handle turns about z at
  // 1 rad/s: R_WT = (cos(t/2), 0, 0, sin(t/2)) with t the driver's time at the reading.
  test::ServerProcess server(driver_config(R"("button_period_s": 0.01, "turn_rate": 1.0)"));
  Client client(config_for(server));
  EXPECT_TRUE(client.device_info().capabilities.orientation);
  EXPECT_EQ(client.device_info().buttons, 1u);
  State s = step_and_get(client, 5);  // tick 5 reads at t = 4 ms: released
  EXPECT_EQ(s.buttons, 0u);
  ASSERT_TRUE(s.orientation.has_value());
  EXPECT_NEAR(s.orientation->w, std::cos(0.002), 1e-12);
  EXPECT_NEAR(s.orientation->z, std::sin(0.002), 1e-12);
  s = step_and_get(client, 10);  // tick 15 reads at t = 14 ms: pressed
  EXPECT_EQ(s.buttons, 1u);
  EXPECT_NEAR(s.orientation->z, std::sin(0.007), 1e-12);
  // The same over UDP (on_state sees datagrams only; the Step reply's state is not passed there).
  std::mutex mutex;
  std::optional<State> streamed;
  client.on_state([&](const State& state) {
    std::lock_guard lock(mutex);
    streamed = state;
  });
  // Datagrams leave on the sender's thread and reach the callback on another: on a loaded
  // machine the steps can outrun them, so step a while and then wait a while.
  const auto seen = [&] {
    std::lock_guard lock(mutex);
    return streamed.has_value();
  };
  for (int i = 0; i < 100 && !seen(); ++i) step_and_get(client, 1);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (!seen() && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  client.on_state({});
  std::lock_guard lock(mutex);
  ASSERT_TRUE(streamed.has_value()) << "no State datagram arrived";
  ASSERT_TRUE(streamed->orientation.has_value());
  const double t = static_cast<double>(streamed->tick - 1) * 1e-3;
  EXPECT_NEAR(streamed->orientation->w, std::cos(0.5 * t), 1e-12);
  EXPECT_NEAR(streamed->orientation->z, std::sin(0.5 * t), 1e-12);
  const double periods = t / 0.01;  // the button's half-periods elapsed; on a boundary either is right
  if (std::abs(periods - std::round(periods)) > 1e-6) {
    EXPECT_EQ(streamed->buttons, static_cast<std::uint64_t>(periods) % 2 == 1 ? 1u : 0u);
  }
}

TEST(DriverDevice, ADeviceWithoutOrientationSendsNone) {
  test::ServerProcess server(driver_config(""));
  Client client(config_for(server));
  EXPECT_FALSE(client.device_info().capabilities.orientation);
  EXPECT_EQ(client.device_info().buttons, 0u);
  const State s = step_and_get(client, 3);
  EXPECT_FALSE(s.orientation.has_value());
  EXPECT_EQ(s.buttons, 0u);
}

TEST(DriverDevice, DeviceClockedTheDriversServoLoopPacesTheTicks) {
  // Real time, paced by the example driver's own 1 kHz servo thread (its run_servo): hapticd's
  // loop thread only answers its callbacks. Behaviour, not timing: ticks advance and the state
  // stream carries the driver's pose; the server stops cleanly, ending the servo loop.
  test::ServerProcess server(
      R"({"udp_address": "127.0.0.1", "status_period_s": 0, "real_time": {"use_fifo": false},
          "driver": {"library": ")" POINT_MASS_DRIVER R"(", "clock": "DEVICE",
                     "params": {"servo_rate_hz": 1000, "initial": [0.02, 0, 0]}}})");
  Client client(config_for(server));
  EXPECT_EQ(client.device_info().loop_rate_hz, 1000.0);
  State s;
  ASSERT_TRUE(client.wait_for_tick(100, s, std::chrono::seconds(10)))
      << "no ticks from the driver's servo loop";
  EXPECT_NEAR(s.position.x, 0.02, 1e-12);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
}

}  // namespace
}  // namespace haptic
