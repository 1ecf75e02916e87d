#include "app/list_devices.hpp"

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "runtime/driver_device.hpp"

namespace haptic::app {

std::vector<std::string> driver_folders(const std::vector<std::string>& extra) {
  std::vector<std::string> candidates = extra;
  std::error_code error;
  const std::filesystem::path binary = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    candidates.push_back((binary.parent_path().parent_path() / HAPTIC_INSTALL_LIBDIR / "hapticd").string());
    // A hapticd run from its build tree also finds the drivers built beside it.
    if (binary.string().rfind(std::string(HAPTIC_BUILD_TREE) + "/", 0) == 0) {
      candidates.push_back(std::string(HAPTIC_BUILD_TREE) + "/driver");
    }
  }
  std::vector<std::string> folders;
  for (const std::string& folder : candidates) {
    std::error_code missing;
    if (!std::filesystem::is_directory(folder, missing)) continue;
    const std::string canonical = std::filesystem::weakly_canonical(folder, missing).string();
    if (std::find(folders.begin(), folders.end(), canonical) == folders.end()) folders.push_back(canonical);
  }
  return folders;
}

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
