#pragma once
// Protobuf messages as the HTTP faces write and read them (the web viewer's resources and the JSON
// face of the control plane): protobuf's JSON mapping, fields named as in the .proto files.

#include <google/protobuf/message.h>

#include <string>
#include <string_view>

namespace haptic::net {

/// `message` as JSON: fields by their proto names (snake_case), zeros and empty fields printed,
/// 64-bit integers as strings and bytes as base64 (protobuf's JSON mapping). Throws
/// std::runtime_error naming the type when it cannot be written.
std::string to_json(const google::protobuf::Message& message);

/// Parses `json` into `message`: fields by either name (proto or lowerCamelCase), an unknown field
/// refused. Returns "" or what is wrong, as protobuf's parser says it (naming the field).
std::string from_json(std::string_view json, google::protobuf::Message& message);

}  // namespace haptic::net
