// Nothing a vendor runtime throws crosses hapticd's C driver ABI (driver.h: "No function may throw
// a C++ exception across this boundary"; driver/vendors/common/driver_adapter.hpp). Each stand-in
// runtime is told to throw from one of its functions at a time (`throw FUNCTION`), for every
// function the driver calls in a device's whole life, and the driver's every entry point is called
// through its C function table as hapticd calls it: each returns a status (or a refusal) rather than
// ending the process, and what was thrown is said by create's error, list_devices' text or
// last_error. Before the adapter, the Force Dimension and OpenHaptics drivers caught nothing outside
// create and list_devices: the first such call ended the test process.
#include <gtest/gtest.h>

#include <dlfcn.h>

#include <cstdlib>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <haptic/driver.h>

#include "driver_test_support.hpp"

namespace haptic::runtime {
namespace {

/// A driver library's function table, opened with dlopen as hapticd opens it.
class DriverLibrary {
 public:
  explicit DriverLibrary(const char* path) {
    handle_ = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) throw std::runtime_error(dlerror());
    auto entry = reinterpret_cast<haptic_driver_entry_fn>(dlsym(handle_, HAPTIC_DRIVER_ENTRY_SYMBOL));
    if (entry == nullptr) throw std::runtime_error(std::string(path) + " has no driver entry point");
    api_ = entry();
  }
  ~DriverLibrary() { dlclose(handle_); }
  DriverLibrary(const DriverLibrary&) = delete;
  DriverLibrary& operator=(const DriverLibrary&) = delete;
  const haptic_driver_api& api() const { return *api_; }

 private:
  void* handle_ = nullptr;
  const haptic_driver_api* api_ = nullptr;
};

/// What one life of a device said: each call's status and the texts that explain failures.
struct Life {
  std::vector<std::string> bad_statuses;  // calls that returned neither OK nor FAILED
  std::string said;                       // every error text the driver gave, one per line
};

bool valid_status(int status) { return status == HAPTIC_DRIVER_OK || status == HAPTIC_DRIVER_FAILED; }

/// A device's whole life through the C table, as hapticd lives it: list, create, describe, start,
/// read and write (`tick` between them: a manual servo clock moves on), the safe state, another
/// read and write, stop, destroy. Every text the driver gives is collected.
Life live(const haptic_driver_api& api, const std::string& params, const std::function<void()>& tick) {
  Life life;
  auto expect_status = [&life](const char* call, int status) {
    if (!valid_status(status)) life.bad_statuses.push_back(std::string(call) + " returned " + std::to_string(status));
  };
  char text[4096] = {};
  const int listed = api.list_devices(params.c_str(), text, sizeof text);
  if (listed < 0) life.said += std::string("list_devices: ") + text + "\n";
  char error[HAPTIC_DRIVER_ERROR_SIZE] = {};
  void* driver = api.create(params.c_str(), error);
  if (driver == nullptr) {
    life.said += std::string("create: ") + error + "\n";
    return life;
  }
  auto after = [&](const char* call) {
    char why[HAPTIC_DRIVER_ERROR_SIZE] = {};
    api.last_error(driver, why);
    if (why[0] != '\0') life.said += std::string(call) + ": " + why + "\n";
  };
  haptic_driver_info info{};
  expect_status("describe", api.describe(driver, &info));
  after("describe");
  expect_status("start", api.start(driver));
  after("start");
  haptic_driver_reading reading{};
  haptic_driver_command command{};
  command.tau[0] = 0.5;
  for (int round = 0; round < 2; ++round) {
    tick();
    expect_status("read", api.read(driver, &reading));
    after("read");
    expect_status("write", api.write(driver, &command, 1e-3));
    after("write");
    if (round == 0) {
      api.enter_safe_state(driver);
      after("enter_safe_state");
    }
  }
  api.stop(driver);
  after("stop");
  api.destroy(driver);
  return life;
}

/// The vendor functions a call log names (each line's first word), in the order first called.
std::vector<std::string> functions_called(const std::string& calls) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  std::istringstream lines(calls);
  std::string line;
  while (std::getline(lines, line)) {
    const std::string name = line.substr(0, line.find(' '));
    if (!name.empty() && seen.insert(name).second) names.push_back(name);
  }
  return names;
}

/// For every function the driver calls in a device's life, a life with that function throwing:
/// each entry point returns a status, and the exception is said somewhere.
void every_function_may_throw(test::StandinLibrary& standin, const char* driver_path, const std::string& params,
                              const std::function<void()>& tick) {
  DriverLibrary library(driver_path);
  standin.clear();
  const Life clean = live(library.api(), params, tick);
  ASSERT_TRUE(clean.bad_statuses.empty());
  const std::vector<std::string> functions = functions_called(standin.calls());
  ASSERT_GE(functions.size(), 10u) << standin.calls();
  for (const std::string& function : functions) {
    SCOPED_TRACE(function);
    ASSERT_EQ(standin.control("reset"), 0);
    ASSERT_EQ(standin.control("throw " + function), 0);
    standin.clear();
    const Life life = live(library.api(), params, tick);
    EXPECT_TRUE(life.bad_statuses.empty()) << life.bad_statuses.front();
    EXPECT_NE(life.said.find(function + " threw"), std::string::npos)
        << "nothing said that " << function << " threw; the driver said:\n"
        << life.said << "calls:\n"
        << standin.calls();
  }
  ASSERT_EQ(standin.control("throw none"), 0);
}

TEST(VendorDriverExceptions, ForceDimensionSurvivesEveryRuntimeFunctionThrowing) {
  setenv("FAKE_DHD_DEVICES", "sigma.7", 1);  // a wrist and a gripper: every function the driver has
  test::StandinLibrary standin(FAKE_FORCEDIMENSION_LIBRARY, "fake_dhd");
  const std::string params = std::string(R"({"library": ")") + FAKE_FORCEDIMENSION_LIBRARY + "\"}";
  every_function_may_throw(standin, FORCEDIMENSION_DRIVER, params, [] {});
}

// On the stand-in's manual clock, so the servo callback's calls (hdBeginFrame, the getters, the
// force) run on this thread at each tick: a throw there is caught on the vendor's thread and the
// device faults, as when a frame cannot be read.
TEST(VendorDriverExceptions, OpenHapticsSurvivesEveryRuntimeFunctionThrowing) {
  setenv("FAKE_HD_DEVICES", "rig=Touch", 1);
  setenv("FAKE_HD_CLOCK", "manual", 1);
  test::StandinLibrary standin(FAKE_OPENHAPTICS_LIBRARY, "fake_hd");
  const std::string params = std::string(R"({"library": ")") + FAKE_OPENHAPTICS_LIBRARY + R"(", "device": "rig"})";
  every_function_may_throw(standin, OPENHAPTICS_DRIVER, params, [&standin] { (void)standin.control("tick 1"); });
}

}  // namespace
}  // namespace haptic::runtime
