// The vendor drivers with the whole server around them (driver/vendors against the stand-ins of
// tests/driver/standins), driven through the SDK as a lab's client would: 3D Systems' OpenHaptics
// paced by the device's own servo loop in real time, and Haply's Inverse Service in lockstep. The
// Force Dimension one is in driver_device_test. Behaviour, not timing: a hand rests on a wall
// where the spring says, an unplugged device faults and is driven again once back.
#include <gtest/gtest.h>

#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#ifdef HAPLY_DRIVER  // the Haply driver is built (HAPTIC_BUILD_HAPLY_DRIVER)
#include "fake_haply_service.hpp"
#endif
#include "integration/sdk_harness.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::config_for;
using test::step_and_get;

/// The state at tick `tick` or later, from the stream (real time: the device's servo paces it).
State state_at(Client& client, std::uint64_t tick) {
  State s;
  if (!client.wait_for_tick(tick, s, std::chrono::seconds(20))) {
    throw std::runtime_error("no tick " + std::to_string(tick) + " within 20 s");
  }
  return s;
}

// The Touch's stand-in takes the hand force in its own frame (y up): 1 N down is (0, −1, 0) there,
// −z in W. Its servo thread ticks at 1 kHz and calls the driver's callback, which runs hapticd's
// tick: the wall 0 m below the stylus's rest holds it 2 mm deep (500 N/m). Unplugged at the
// stand-in's tick 3000 and plugged in again at 3300, the device faults (zero force) and is driven
// again without a restart.
TEST(VendorDevice, AnOpenHapticsTouchPacedByItsServoLoopRestsOnAWallFaultsAndComesBack) {
  setenv("FAKE_HD_DEVICES", "Default Device=Touch", 1);
  setenv("FAKE_HD_SCRIPT",
         "0 hand Default Device 0 -1 0;3000 unplug Default Device;3300 replug Default Device", 1);
  test::ServerProcess server(R"({"udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "driver": {"library": ")" OPENHAPTICS_DRIVER R"(", "clock": "DEVICE",
                 "params": {"library": ")" FAKE_OPENHAPTICS_LIBRARY R"("}}})");
  unsetenv("FAKE_HD_SCRIPT");
  unsetenv("FAKE_HD_DEVICES");
  Client client(config_for(server));
  EXPECT_NE(client.device_info().name.find("Touch"), std::string::npos) << client.device_info().name;
  EXPECT_EQ(client.device_info().loop_rate_hz, 1000.0);
  auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1}, .impedance = {500.0, 5.0}});
  State s = state_at(client, 2500);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.position.z, -1.0 / 500.0, 5e-5);
  EXPECT_NEAR(s.force.z, 1.0, 2e-2);
  // The stand-in counts its own ticks, which start before hapticd's first: look for the fault
  // after tick 3000 and for its end after 3300, each within a bounded number of ticks.
  std::uint64_t tick = s.tick;
  do {
    s = state_at(client, tick += 10);
  } while ((s.flags & kDeviceFault) == 0 && tick < 6000);
  ASSERT_NE(s.flags & kDeviceFault, 0u) << "no fault by tick 6000";
  EXPECT_EQ(s.force, (Vec3{0, 0, 0}));
  do {
    s = state_at(client, tick += 10);
  } while ((s.flags & kDeviceFault) != 0 && tick < 9000);
  ASSERT_EQ(s.flags & kDeviceFault, 0u) << "still faulted at tick 9000";
  s = state_at(client, tick + 2500);  // driven again: back on the wall
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_NEAR(s.position.z, -1.0 / 500.0, 5e-5);
  EXPECT_NEAR(s.force.z, 1.0, 2e-2);
}

#ifdef HAPLY_DRIVER
/// Steps `ticks` ticks in chunks of 250: each Haply tick is a WebSocket round trip, and a long
/// Step under the sanitizers would outlast the SDK's deadline for one call.
State step_in_chunks(Client& client, std::uint32_t ticks) {
  State s;
  for (std::uint32_t done = 0; done < ticks; done += 250) s = step_and_get(client, std::min<std::uint32_t>(250, ticks - done));
  return s;
}

// The Inverse3 behind the stand-in of Haply's Inverse Service, which this test runs on a thread of
// its own; hapticd connects to it over the WebSocket as to the real service, in lockstep (each
// tick one message and its answer). The cursor rests at §3.4's position, z = 0.143 m in W; the
// stand-in's 1 N hand (−Z in Haply's frame, −z in W) rests on a 500 N/m wall there 2 mm deep.
TEST(VendorDevice, AHaplyInverse3RestsOnAWallInLockstepAndFaultsWhenUnplugged) {
  fake_haply::Options options;
  options.port = 0;
  fake_haply::Service service(options);
  std::string error;
  ASSERT_TRUE(service.start(&error)) << error;
  const std::string url = "ws://127.0.0.1:" + std::to_string(service.port());
  test::ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "driver": {"library": ")" HAPLY_DRIVER R"(", "call_timeout_ms": 5000,
                 "params": {"url": ")" + url + R"(", "reply_timeout_ms": 2000}}})");
  Client client(config_for(server));
  EXPECT_EQ(client.device_info().name, "Haply Inverse3 049D with VerseGrip 0");
  State s = step_and_get(client, 2);
  const double rest_z = s.position.z;
  EXPECT_NEAR(rest_z, 0.143, 1e-6);
  ASSERT_EQ(service.control("hand 049D 0 0 -1"), "ok");
  auto wall = client.add_wall({.point = {0, 0, rest_z}, .normal = {0, 0, 1}, .impedance = {500.0, 5.0}});
  s = step_in_chunks(client, 3000);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.contact_count, 1u);
  EXPECT_NEAR(s.position.z - rest_z, -1.0 / 500.0, 5e-5);
  EXPECT_NEAR(s.force.z, 1.0, 2e-2);
  ASSERT_EQ(service.control("unplug 049D"), "ok");
  s = step_and_get(client, 5);
  EXPECT_NE(s.flags & kDeviceFault, 0u);
  EXPECT_EQ(s.force, (Vec3{0, 0, 0}));
  ASSERT_EQ(service.control("replug 049D"), "ok");
  s = step_in_chunks(client, 2000);
  EXPECT_EQ(s.flags & kDeviceFault, 0u);
  EXPECT_NEAR(s.position.z - rest_z, -1.0 / 500.0, 5e-5);
  service.stop();
}
#endif

}  // namespace
}  // namespace haptic
