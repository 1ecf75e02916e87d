#include "net/proto_json.hpp"

#include <google/protobuf/util/json_util.h>

#include <stdexcept>

namespace haptic::net {

std::string to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string out;
  if (const auto status = google::protobuf::util::MessageToJsonString(message, &out, options); !status.ok()) {
    throw std::runtime_error("cannot write " + message.GetTypeName() + " as JSON: " + status.ToString());
  }
  return out;
}

std::string from_json(std::string_view json, google::protobuf::Message& message) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &message, options);
  if (status.ok()) return {};
  const std::string text(status.message());
  return text.empty() ? status.ToString() : text;
}

}  // namespace haptic::net
