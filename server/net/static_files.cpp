#include "net/static_files.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace haptic::net {
namespace {

constexpr std::uintmax_t kMaxFileBytes = 16u << 20;

const char* content_type_of(const std::filesystem::path& file) {
  const std::string extension = file.extension().string();
  if (extension == ".html") return "text/html; charset=utf-8";
  if (extension == ".js" || extension == ".mjs") return "text/javascript; charset=utf-8";
  if (extension == ".css") return "text/css; charset=utf-8";
  if (extension == ".json" || extension == ".map") return "application/json";
  if (extension == ".png") return "image/png";
  if (extension == ".svg") return "image/svg+xml";
  if (extension == ".ico") return "image/x-icon";
  return "application/octet-stream";
}

}  // namespace

void StaticFiles::load(const std::filesystem::path& root, const std::string& field) {
  files_.clear();
  if (!std::filesystem::is_regular_file(root / "index.html")) {
    throw std::runtime_error(field + ": no index.html in '" + root.string() +
                             "' (a build puts the page into its share/hapticd/web once scripts/setup "
                             "has run npm ci in web/)");
  }
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    const std::string name = entry.path().string();
    if (entry.is_symlink()) {
      throw std::runtime_error(field + ": '" + name + "' is a symbolic link; the page's folder "
                               "must hold its files themselves");
    }
    if (!entry.is_regular_file()) continue;  // folders (walked into), sockets and the like
    if (entry.file_size() > kMaxFileBytes) {
      throw std::runtime_error(field + ": '" + name + "' is larger than 16 MiB");
    }
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream bytes;
    // (Streaming an empty file sets failbit without a failure.)
    if (!in || (entry.file_size() > 0 && !(bytes << in.rdbuf()))) {
      throw std::runtime_error(field + ": cannot read '" + name + "'");
    }
    HttpResponse file;
    file.content_type = content_type_of(entry.path());
    file.body = bytes.str();
    file.headers.emplace_back("Cache-Control", "no-cache");
    files_["/" + entry.path().lexically_relative(root).generic_string()] = std::move(file);
  }
}

const HttpResponse* StaticFiles::find(const std::string& path) const {
  const auto found = files_.find(path == "/" ? "/index.html" : path);
  return found == files_.end() ? nullptr : &found->second;
}

}  // namespace haptic::net
