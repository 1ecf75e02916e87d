#include "haptic/io/bounded_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace haptic::io {

std::string read_bounded_file(const std::string& path, std::size_t max_bytes, const std::string& what,
                              std::string& out) {
  out.clear();
  std::ifstream file(path, std::ios::binary);
  if (!file) return "'" + path + "': cannot open: " + std::strerror(errno);
  // In chunks, so that a device or a pipe with no end stops at the bound.
  char chunk[64 * 1024];
  while (file.read(chunk, sizeof chunk) || file.gcount() > 0) {
    out.append(chunk, static_cast<std::size_t>(file.gcount()));
    if (out.size() > max_bytes) {
      out.clear();
      return "'" + path + "': larger than " + std::to_string(max_bytes >> 20) + " MiB, the most read for " +
             what;
    }
  }
  if (file.bad()) return "'" + path + "': cannot read: " + std::strerror(errno);
  return {};
}

}  // namespace haptic::io
