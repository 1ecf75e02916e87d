#pragma once
// The driver test kit: what any driver owes hapticd, checked against a driver library as hapticd
// loads it (runtime::DriverDevice). It loads and describes itself sanely; it refuses a params key
// it does not take, and each given option with a value of the wrong kind, naming it; 200 ticks of reading
// and a zero command give finite, fresh readings, the safe state can be entered at any time and a
// write after it is taken (driver.h);
// for a Cartesian driver, 5 % of max_force along each axis of W for 20 ms moves the tool along
// that axis, positively, with at least 90 % of the motion on it. It commands forces: run it on
// hardware that is free to move. The program haptic-driver-kit runs it (docs/devices.md).

#include <ostream>
#include <string>
#include <vector>

namespace haptic::driver_kit {

struct KitOptions {
  std::string library;             // the driver's shared library
  std::string params_json = "{}";  // what its create() gets
  bool cartesian = true;           // false: the Cartesian checks are skipped
  /// Longest a read or write may take before it is a hang (DriverOptions::call_timeout_s);
  /// hapticd's default. On a loaded host without real-time scheduling, raise it (docs/devices.md).
  double call_timeout_s = 0.02;
};

struct CheckResult {
  std::string name;    // what was checked, as a sentence
  bool passed = false;
  bool skipped = false;
  std::string detail;  // why it failed or was skipped; what was seen
};

/// Runs every check in turn, each on a fresh instance of the driver; a driver that throws or
/// fails a call fails that check, not the kit. `log` gets one line about the driver first.
std::vector<CheckResult> run_kit(const KitOptions& options, std::ostream& log);

}  // namespace haptic::driver_kit
