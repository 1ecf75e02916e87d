#pragma once
// `hapticd --list-devices`: every driver library hapticd can find, and the devices each says it
// can open on this host (driver ABI 2's list_devices), with the params that open each.

#include <ostream>
#include <string>
#include <vector>

namespace haptic::app {

/// The folders searched, in order: each of `extra` (--driver-dir), the installed drivers
/// (<prefix>/<libdir>/hapticd beside the binary's bin/), and, for a hapticd run from its build
/// tree, that tree's driver/ folder. Missing folders are left out.
std::vector<std::string> driver_folders(const std::vector<std::string>& extra);

/// Lists each *.so of `folders` (sorted) and what it sees on `out`; returns the exit status, 0
/// (a library that cannot be asked is reported, not an error: its line says what to install).
int list_devices_command(const std::vector<std::string>& folders, std::ostream& out);

}  // namespace haptic::app
