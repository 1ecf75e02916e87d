#pragma once
// `hapticd --list-devices`: every driver library hapticd can find, and the devices each says it
// can open on this host (driver ABI 2's list_devices), with the params that open each.

#include <ostream>
#include <string>
#include <vector>

namespace haptic::app {

/// Lists each *.so of `folders` (sorted; runtime::driver_folders gives hapticd's own) and what it sees on `out`; returns the exit status, 0
/// (a library that cannot be asked is reported, not an error: its line says what to install).
int list_devices_command(const std::vector<std::string>& folders, std::ostream& out);

}  // namespace haptic::app
