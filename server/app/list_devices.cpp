#include "app/list_devices.hpp"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "runtime/driver_device.hpp"

namespace haptic::app {

int list_devices_command(const std::vector<std::string>& folders, std::ostream& out) {
  std::size_t libraries = 0, devices = 0;
  for (const std::string& folder : folders) {
    std::vector<std::filesystem::path> found;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
      if (entry.path().extension() == ".so" && entry.is_regular_file()) found.push_back(entry.path());
    }
    std::sort(found.begin(), found.end());
    for (const auto& library : found) {
      const runtime::DriverListing listing = runtime::list_driver_devices(library.string());
      if (!listing.is_driver) continue;  // another library in the folder
      ++libraries;
      out << library.string();
      if (listing.abi_version > 0) out << " (driver ABI " << listing.abi_version << ")";
      out << ": ";
      if (!listing.error.empty()) {
        out << "cannot ask: " << listing.error << "\n";
      } else if (!listing.can_list) {
        out << "cannot list its devices (no list_devices); configure it by its documentation\n";
      } else {
        out << listing.devices.size() << (listing.devices.size() == 1 ? " device" : " devices") << "\n";
        for (const auto& device : listing.devices) {
          out << "  \"params\": " << device.params_json << "   " << device.description << "\n";
        }
        devices += listing.devices.size();
      }
    }
  }
  if (libraries == 0) {
    out << "no driver libraries found (searched:";
    for (const std::string& folder : folders) out << " " << folder;
    out << (folders.empty() ? " nothing" : "") << "); --driver-dir DIR adds a folder\n";
  } else {
    out << devices << (devices == 1 ? " device" : " devices") << " from " << libraries
        << (libraries == 1 ? " driver" : " drivers")
        << "; use one as {\"driver\": {\"library\": \"...\", \"params\": ...}} (docs/devices.md)\n";
  }
  return 0;
}

}  // namespace haptic::app
