#include "haptic/io/scene_file.hpp"

#include <google/protobuf/util/json_util.h>

#include <fstream>
#include <sstream>

namespace haptic::io {

std::string read_scene_file(const std::string& path, v1::Scene& out) {
  std::ifstream file(path);
  if (!file) return path + ": cannot open";
  std::stringstream text;
  text << file.rdbuf();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(text.str(), &out, options);
  if (!status.ok()) return path + ": not a valid Scene: " + std::string(status.message());
  return {};
}

}  // namespace haptic::io
