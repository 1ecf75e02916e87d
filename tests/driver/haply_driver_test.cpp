// The Haply driver (driver/vendors/haply) end to end against the stand-in of Haply's Inverse
// Service (tests/driver/standins: a WebSocket service over a simulated Inverse3 and VerseGrip,
// run in-process on a free port): the real driver code, loaded by hapticd's DriverDevice. The
// service steps its plant once per message, so the physics is exact whatever the machine's load.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <thread>

#include "driver_kit.hpp"
#include "driver_test_support.hpp"
#include "fake_haply_service.hpp"
#include "runtime/cartesian_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::runtime {
namespace {

constexpr double kT = 1e-3;  // s

/// The stand-in service on a free port, for one test.
class Service {
 public:
  explicit Service(const std::string& devices = fake_haply::kDefaultDevices) {
    fake_haply::Options options;
    options.port = 0;
    options.devices = devices;
    service_ = std::make_unique<fake_haply::Service>(options);
    std::string error;
    if (!service_->start(&error)) throw std::runtime_error(error);
  }
  std::string url() const { return "ws://127.0.0.1:" + std::to_string(service_->port()); }
  std::string control(const std::string& command) { return service_->control(command); }
  void stop() { service_->stop(); }

 private:
  std::unique_ptr<fake_haply::Service> service_;
};

std::string params(const Service& service, const std::string& extra = {}) {
  return R"({"url": ")" + service.url() + "\"" + (extra.empty() ? "" : ", " + extra) + "}";
}

/// The driver waiting for each answer of the service as long as it takes (a loaded machine, the
/// sanitizers), so every read takes the answer to the tick before: exact, whatever the timing.
DriverOptions haply(const Service& service, const std::string& extra = {}) {
  DriverOptions options = test::driver_options(
      HAPLY_DRIVER, params(service, std::string(R"("reply_timeout_ms": 2000)") + (extra.empty() ? "" : ", " + extra)));
  return options;
}

using test::refusal;

TEST(Haply, ChoosesTheDevicesFromTheInventoryAndDescribesThemInW) {
  Service service;
  DriverDevice device(haply(service));
  const DeviceDescription& d = device.description();
  EXPECT_EQ(d.name, "Haply Inverse3 049D with VerseGrip 0");
  EXPECT_EQ(d.buttons, 3u);  // the wireless grip's a, b, c
  EXPECT_TRUE(d.capabilities.orientation);
  // Centred on the cursor's rest position (§3.4's (0.078, -0.148, 0.143) m in Haply's frame),
  // which in W = (-Y, X, Z) is (0.148, 0.078, 0.143).
  EXPECT_NEAR(0.5 * (d.workspace_min.x + d.workspace_max.x), 0.148, 1e-9);
  EXPECT_NEAR(0.5 * (d.workspace_min.y + d.workspace_max.y), 0.078, 1e-9);
  EXPECT_NEAR(0.5 * (d.workspace_min.z + d.workspace_max.z), 0.143, 1e-9);
}

// A 500 N/m wall on W's z holds the stand-in's 1 N hand (down: -Z in Haply's frame) 2 mm deep:
// one message a tick, each answered with the state the next tick reads.
TEST(Haply, AWallHoldsAHandWhereTheSpringSays) {
  Service service;
  DriverDevice device(haply(service));
  CartesianModel model;
  DevicePort port(device, model);
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  ASSERT_EQ(service.control("hand 049D 0 0 -1"), "ok");
  ToolReading tool;
  ASSERT_EQ(port.read(tool), DeviceStatus::kOk);
  const double z0 = tool.p_WT.z;
  for (int k = 0; k < 4000; ++k) {
    const double z = tool.p_WT.z - z0;
    const engine::Vec3 F{0.0, 0.0, z < 0.0 ? -500.0 * z - 5.0 * tool.v_WT.z : 0.0};
    ASSERT_EQ(port.write(ToolCommand{F}, kT), DeviceStatus::kOk);
    ASSERT_EQ(port.read(tool), DeviceStatus::kOk) << "tick " << k;
  }
  EXPECT_NEAR(tool.p_WT.z - z0, -1.0 / 500.0, 5e-5);
  device.stop();
}

TEST(Haply, PassesTheDriverKit) {
  Service service;
  std::ostringstream log;
  for (const auto& result : driver_kit::run_kit({HAPLY_DRIVER, params(service), true, test::kTestCallTimeoutS}, log)) {
    EXPECT_TRUE(result.passed) << result.name << ": " << result.detail << "\n" << log.str();
  }
}

TEST(Haply, TheGripsOrientationAndButtonsAreRead) {
  Service service;
  DriverDevice device(haply(service));
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  // A quarter turn about Haply's Z (up), which is W's z too; button b.
  ASSERT_EQ(service.control("orientation 0 0.70710678 0 0 0.70710678"), "ok");
  ASSERT_EQ(service.control("button 0 b 1"), "ok");
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_NEAR(reading.R_WT.w, std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(reading.R_WT.z, std::sqrt(0.5), 1e-6);
  EXPECT_EQ(reading.buttons, 2u);
  device.stop();
}

/// Starts `device` and reads once; then the control command `fault` must make the read after a
/// write an error, and `recover` the one after that a reading again. Returns the error's reason.
std::string fault_then_recovery(Service& service, DriverDevice& device, const std::string& fault,
                                const std::string& recover) {
  EXPECT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
  EXPECT_EQ(service.control(fault), "ok");
  EXPECT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  EXPECT_EQ(device.read(reading), DeviceStatus::kError);
  const std::string reason = device.fault_reason();
  EXPECT_EQ(service.control(recover), "ok");
  EXPECT_EQ(device.write(DeviceCommand{}, kT), DeviceStatus::kOk);
  EXPECT_EQ(device.read(reading), DeviceStatus::kOk);
  return reason;
}

TEST(Haply, AnUnpluggedDeviceFaultsSayingSoAndComesBack) {
  Service service;
  DriverDevice device(haply(service));
  const std::string reason = fault_then_recovery(service, device, "unplug 049D", "replug 049D");
  // In the service's words (it refuses a command for a device it lost) or the driver's.
  EXPECT_NE(reason.find("049D"), std::string::npos) << reason;
  EXPECT_NE(reason.find("unplugged"), std::string::npos) << reason;
  EXPECT_EQ(device.fault_reason(), "");
  device.stop();
}

// A service that answers what the driver does not expect (a position's coordinate as a string):
// the JSON library throws reading it, and that used to cross the C ABI and end hapticd. Now the
// read fails, saying why, and the next good answer reads again.
TEST(Haply, AnAnswerItCannotReadIsAFaultNotACrash) {
  Service service;
  DriverDevice device(haply(service));
  const std::string reason = fault_then_recovery(service, device, "garble 049D", "ungarble 049D");
  EXPECT_NE(reason.find("the driver failed"), std::string::npos) << reason;
  // enter_safe_state from another thread beside the loop's writes, as hapticd's watchdog calls it:
  // both build messages (the session's handshake flag is atomic now), and the process lives.
  std::thread safe([&] {
    for (int i = 0; i < 50; ++i) device.enter_safe_state();
  });
  for (int i = 0; i < 50; ++i) (void)device.write(DeviceCommand{}, kT);
  safe.join();
  device.stop();
}

// The same in the inventory create() reads: a refusal saying so, not a crash; the listing, which
// reads only the ids, still lists the device.
TEST(Haply, AnInventoryItCannotReadIsARefusalNotACrash) {
  Service service;
  ASSERT_EQ(service.control("garble 049D"), "ok");
  const std::string why = refusal(haply(service));
  EXPECT_NE(why.find("create() refused: the driver failed: "), std::string::npos) << why;
  EXPECT_EQ(list_driver_devices(HAPLY_DRIVER, params(service)).devices.size(), 1u);
}

// driver.h: enter_safe_state sends a message without a force (the device idles, §3.3) and the
// next write drives the device again, returning OK.
TEST(Haply, AfterTheSafeStateTheNextWriteDrivesTheDeviceAgain) {
  Service service;
  DriverDevice device(haply(service));
  ASSERT_EQ(device.start(), DeviceStatus::kOk);
  DeviceReading reading;
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  DeviceCommand push;
  push.tau[0] = 1.0;
  ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(service.control("clear"), "ok");
  device.enter_safe_state();
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
  ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
  const std::string calls = service.control("calls");
  const std::size_t idle = calls.find("probe_position"), force = calls.find("set_cursor_force");
  ASSERT_NE(idle, std::string::npos) << calls;
  ASSERT_NE(force, std::string::npos) << calls;
  EXPECT_LT(idle, force) << calls;  // the safe state's message first, then the write's force
  EXPECT_EQ(calls.find("set_cursor_force", force + 1), std::string::npos) << calls;
  device.stop();
}

// Both forms of set_cursor_force (§3.3: the 3.5 documentation's "vector", 3.1-era clients'
// "values") push the same way.
TEST(Haply, EitherForceFormPushesTheCursor) {
  for (const char* key : {"vector", "values"}) {
    Service service;
    DriverDevice device(haply(service, std::string(R"("force_key": ")") + key + "\""));
    ASSERT_EQ(device.start(), DeviceStatus::kOk);
    DeviceReading reading;
    ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    const double x0 = reading.q[0];
    DeviceCommand push;
    push.tau[0] = 1.0;  // towards the operator: -Y in Haply's frame
    for (int k = 0; k < 50; ++k) {
      ASSERT_EQ(device.write(push, kT), DeviceStatus::kOk);
      ASSERT_EQ(device.read(reading), DeviceStatus::kOk);
    }
    EXPECT_GT(reading.q[0] - x0, 1e-4) << key;
    EXPECT_NE(service.control("calls").find("set_cursor_force"), std::string::npos) << key;
    device.stop();
  }
}

TEST(Haply, ListsTheServicesDevicesAndRefusesWhatIsMissing) {
  Service service;
  const DriverListing listing = list_driver_devices(HAPLY_DRIVER, params(service));
  ASSERT_EQ(listing.error, "");
  ASSERT_EQ(listing.devices.size(), 1u);
  EXPECT_EQ(listing.devices[0].params_json, R"({"device_id": "049D"})");
  EXPECT_EQ(listing.devices[0].description, "Haply Inverse3 049D (right-handed)");
  const std::string unknown = refusal(haply(service, R"("device_id": "FFFF")"));
  EXPECT_NE(unknown.find("params.device_id \"FFFF\": the service lists 049D"), std::string::npos) << unknown;
  EXPECT_NE(refusal(haply(service, R"("force_key": "vec")")).find("params.force_key"), std::string::npos);
  const std::string url = service.url();
  service.stop();
  const std::string gone = refusal(test::driver_options(HAPLY_DRIVER, R"({"url": ")" + url + "\"}"));
  EXPECT_NE(gone.find("no Haply Inverse Service answers at " + url), std::string::npos) << gone;
}

}  // namespace
}  // namespace haptic::runtime
