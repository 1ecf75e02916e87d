#include "haptic/io/scene_file.hpp"

#include <google/protobuf/util/json_util.h>

#include "haptic/io/bounded_file.hpp"

namespace haptic::io {

std::string read_scene_file(const std::string& path, v1::Scene& out) {
  std::string text;
  if (std::string error = read_bounded_file(path, kMaxSceneFileBytes, "a scene file", text); !error.empty()) {
    return error;
  }
  return parse_scene_json(text, path, out);
}

std::string parse_scene_json(const std::string& text, const std::string& source, v1::Scene& out) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &out, options);
  if (!status.ok()) return source + ": not a valid Scene: " + std::string(status.message());
  return {};
}

std::string scene_json(const v1::Scene& scene) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.preserve_proto_field_names = true;
  std::string text;
  (void)google::protobuf::util::MessageToJsonString(scene, &text, options);
  return text;
}

}  // namespace haptic::io
