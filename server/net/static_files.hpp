#pragma once
// A folder of files served as they are (the web viewer's page), read once at start: every regular
// file under it, by its path from the folder ("/" is "/index.html"), with the content type its
// extension names. Nothing is read from the disk while serving, so no request reaches a file the
// folder did not hold at start.

#include <filesystem>
#include <map>
#include <string>

#include "net/http_server.hpp"

namespace haptic::net {

class StaticFiles {
 public:
  /// Reads every regular file under `root`. Throws std::runtime_error naming `field` when `root`
  /// holds no index.html, and naming the file when one cannot be read, is larger than 16 MiB or
  /// is a symbolic link (which could lead out of the folder).
  void load(const std::filesystem::path& root, const std::string& field);
  /// The file at `path`, or nullptr.
  const HttpResponse* find(const std::string& path) const;

 private:
  std::map<std::string, HttpResponse> files_;
};

}  // namespace haptic::net
