#include "driver_kit.hpp"

#include <chrono>
#include <cstdint>
#include <cmath>
#include <exception>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "runtime/cartesian_model.hpp"
#include "runtime/device_port.hpp"
#include "runtime/driver_device.hpp"

namespace haptic::driver_kit {
namespace {

constexpr double kT = 1e-3;  // the loop's period the kit calls at. Unit: s.

/// Waits out one period, as hapticd's loop would between ticks: a device that samples on its own
/// clock (a vendor runtime's servo thread) must have a new sample for each tick, not for each call.
void next_tick() { std::this_thread::sleep_for(std::chrono::duration<double>(kT)); }

/// Ticks without a new sample before the kit calls a reading stale: a device that samples on its
/// own clock at the loop's rate may repeat one now and then on a busy machine (hapticd's own limit
/// is the configuration's stale_after); a device that stopped sampling never moves again.
constexpr std::uint32_t kStaleAfterTicks = 50;

runtime::DriverOptions driver_options(const KitOptions& options) {
  runtime::DriverOptions out;
  out.library = options.library;
  out.params_json = options.params_json;
  out.stale_after = kStaleAfterTicks;
  out.call_timeout_s = options.call_timeout_s;
  return out;
}

/// A check's body: returns "" when it holds, else what was wrong.
using Body = std::string (*)(const KitOptions&, std::ostream&);

std::string describes_itself(const KitOptions& options, std::ostream& log) {
  runtime::DriverDevice device(driver_options(options));
  const runtime::DeviceDescription& d = device.description();
  log << "  " << d.name << ": " << d.joints << " joints, " << d.dof << " DOF, " << d.buttons
      << " buttons, max force " << d.max_force << " N\n";
  if (d.name.empty()) return "its description has no name";
  if (d.joints < 1 || d.joints > runtime::kMaxJoints) {
    return "joints: " + std::to_string(d.joints) + ", expected 1 to " + std::to_string(runtime::kMaxJoints);
  }
  if (!(d.max_force > 0.0)) return "max_force must be > 0, got " + std::to_string(d.max_force);
  if (!(d.workspace_min.x <= d.workspace_max.x && d.workspace_min.y <= d.workspace_max.y &&
        d.workspace_min.z <= d.workspace_max.z)) {
    return "its workspace's minimum is not below its maximum on every axis";
  }
  if (options.cartesian && d.joints < 3) {
    return "a Cartesian driver's joints 0..2 are x, y, z: it declares " + std::to_string(d.joints);
  }
  return {};
}

/// `params_json` with `"key": value` added as its first member.
std::string with_member(const std::string& params_json, const std::string& member) {
  const auto open = params_json.find('{');
  if (open == std::string::npos) return params_json;
  const auto next = params_json.find_first_not_of(" \t\r\n", open + 1);
  const bool empty = next == std::string::npos || params_json[next] == '}';
  return params_json.substr(0, open + 1) + member + (empty ? "" : ", ") + params_json.substr(open + 1);
}

/// "" when creating the driver with `params_json` is refused naming `name`; else what happened.
std::string refused_naming(const KitOptions& options, const std::string& params_json, const std::string& name,
                           const std::string& what_it_was) {
  KitOptions changed = options;
  changed.params_json = params_json;
  try {
    runtime::DriverDevice device(driver_options(changed));
  } catch (const std::exception& error) {
    if (std::string(error.what()).find(name) != std::string::npos) return {};
    return "it refused " + what_it_was + " without naming '" + name + "': " + error.what();
  }
  return "it took " + what_it_was + " without a word (" + params_json +
         "): a misspelt or mistyped option would leave its default in force unseen";
}

std::string refuses_params_it_does_not_take(const KitOptions& options, std::ostream& log) {
  const std::string unknown = "haptic_kit_not_an_option";
  if (std::string why = refused_naming(options, with_member(options.params_json, "\"" + unknown + "\": 1"),
                                       unknown, "a key it does not have");
      !why.empty()) {
    return why;
  }
  // Each option given, with a value no flat option takes (an object): refused, naming it.
  const nlohmann::json given = nlohmann::json::parse(options.params_json, nullptr, false);
  std::size_t retyped = 0;
  if (given.is_object()) {
    for (const auto& [key, value] : given.items()) {
      nlohmann::json changed = given;
      changed[key] = nlohmann::json::object({{"haptic_kit", true}});
      if (std::string why = refused_naming(options, changed.dump(), key, "an object as params." + key);
          !why.empty()) {
        return why;
      }
      ++retyped;
    }
  }
  log << "  params: an unknown key refused by name" << (retyped > 0 ? ", and each of the " : "")
      << (retyped > 0 ? std::to_string(retyped) + " given with a value of the wrong kind" : std::string())
      << "\n";
  return {};
}

std::string reads_and_takes_commands(const KitOptions& options, std::ostream& /*log*/) {
  runtime::DriverDevice device(driver_options(options));
  if (device.start() != runtime::DeviceStatus::kOk) return "start() failed";
  runtime::DeviceReading reading;
  std::string why;
  for (int k = 0; k < 200 && why.empty(); ++k) {
    if (device.read(reading) != runtime::DeviceStatus::kOk) {
      why = "read() failed at tick " + std::to_string(k);
      if (device.stale_readings() > 0) {
        why += ": its sample sequence stood still for " + std::to_string(kStaleAfterTicks) +
               " readings (stale); it must move with every new sample";
      }
      break;
    }
    for (std::uint32_t j = 0; j < device.description().joints; ++j) {
      if (!std::isfinite(reading.q[j]) || !std::isfinite(reading.q_dot[j])) {
        why = "a reading that is not finite at tick " + std::to_string(k) + ", joint " + std::to_string(j);
        break;
      }
    }
    if (why.empty() && device.write(runtime::DeviceCommand{}, kT) != runtime::DeviceStatus::kOk) {
      why = "write() of a zero command failed at tick " + std::to_string(k);
    }
    next_tick();
  }
  if (why.empty() && device.stale_readings() > 0) {
    why = std::to_string(device.stale_readings()) +
          " stale readings: the sample sequence must move with every new sample";
  }
  device.enter_safe_state();  // callable at any time
  // driver.h: a write after enter_safe_state is hapticd commanding the device again (its zero
  // command first); a device still in its safe state is not a failed call.
  if (why.empty() && device.write(runtime::DeviceCommand{}, kT) != runtime::DeviceStatus::kOk) {
    why = "write() of a zero command right after enter_safe_state() failed: a write after the safe state "
          "must be taken (driver.h), the device staying safe as long as it must";
  }
  device.stop();
  return why;
}

std::string axes_are_those_of_w(const KitOptions& options, std::ostream& log) {
  // A small force along each axis of W in turn moves the tool point along that axis, positively:
  // a swapped or negated axis, or a force read as something else, shows here.
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    runtime::DriverDevice device(driver_options(options));
    runtime::CartesianModel model;
    runtime::DevicePort port(device, model);
    if (device.start() != runtime::DeviceStatus::kOk) return "start() failed";
    runtime::ToolReading start, end;
    if (port.read(start) != runtime::DeviceStatus::kOk) return "read() failed";
    engine::Vec3 F;
    (axis == 0 ? F.x : axis == 1 ? F.y : F.z) = 0.05 * device.description().max_force;
    for (int k = 0; k < 20; ++k) {
      next_tick();
      if (port.write(runtime::ToolCommand{F}, kT) != runtime::DeviceStatus::kOk ||
          port.read(end) != runtime::DeviceStatus::kOk) {
        device.stop();
        return std::string("a call failed while pushing along ") + kAxis[axis];
      }
    }
    device.stop();
    const engine::Vec3 moved = end.p_WT - start.p_WT;
    const double along = axis == 0 ? moved.x : axis == 1 ? moved.y : moved.z;
    std::ostringstream seen;
    seen << "pushed along " << kAxis[axis] << ", the tool moved (" << moved.x << ", " << moved.y
         << ", " << moved.z << ") m";
    log << "  " << seen.str() << "\n";
    if (!(along > 0.0)) return seen.str() + ": not along +" + kAxis[axis];
    if (!(along > 0.9 * engine::norm(moved))) return seen.str() + ": mostly off the axis";
  }
  return {};
}

}  // namespace

std::vector<CheckResult> run_kit(const KitOptions& options, std::ostream& log) {
  struct Check {
    const char* name;
    Body body;
    bool cartesian_only;
  };
  static const Check kChecks[] = {
      {"it loads and describes itself sanely", describes_itself, false},
      {"its readings are finite and fresh, zero commands are taken, the safe state can be entered and a "
       "write after it is taken",
       reads_and_takes_commands, false},
      {"a force along each axis of W moves the tool along that axis", axes_are_those_of_w, true},
      {"it refuses params it does not take, and values of the wrong kind, naming them",
       refuses_params_it_does_not_take, false},
  };
  std::vector<CheckResult> results;
  for (const Check& check : kChecks) {
    CheckResult result;
    result.name = check.name;
    if (check.cartesian_only && !options.cartesian) {
      result.skipped = true;
      result.detail = "not a Cartesian driver";
    } else {
      try {
        result.detail = check.body(options, log);
        result.passed = result.detail.empty();
      } catch (const std::exception& error) {
        result.detail = error.what();  // it did not load, or refused to be created
      }
    }
    results.push_back(std::move(result));
  }
  return results;
}

}  // namespace haptic::driver_kit
