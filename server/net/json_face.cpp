#include "net/json_face.hpp"

#include <array>
#include <cstdint>
#include <exception>

#include "net/proto_json.hpp"

namespace haptic::net {
namespace {

using Codec = BodyCodec;

template <typename Message>
std::string decode(std::string_view body, Codec codec, Message& message) {
  if (codec == Codec::kProto) {
    if (message.ParseFromArray(body.data(), static_cast<int>(body.size()))) return {};
    return "not a " + message.GetTypeName() + " in protobuf's binary form";
  }
  // An empty body is the empty message, as "{}" is.
  return body.empty() ? std::string() : from_json(body, message);
}

FaceReply ok_reply(const google::protobuf::Message& response, Codec codec) {
  FaceReply reply;
  if (codec == Codec::kProto) {
    reply.content_type = "application/proto";
    reply.body = response.SerializeAsString();
  } else {
    reply.content_type = "application/json";
    reply.body = to_json(response);
  }
  return reply;
}

/// One call through the service's handler: the body decoded, the handler run, its reply encoded.
template <typename Request, typename Response,
          grpc::Status (HapticService::*handler)(CallContext*, const Request*, Response*)>
FaceReply run(HapticService& service, std::string_view body, Codec codec, CallContext& context) {
  Request request;
  if (const std::string error = decode(body, codec, request); !error.empty()) {
    return error_reply({grpc::StatusCode::INVALID_ARGUMENT, "request body: " + error});
  }
  Response response;
  const grpc::Status status = (service.*handler)(&context, &request, &response);
  if (!status.ok()) return error_reply(status);
  return ok_reply(response, codec);
}

struct Entry {
  FaceMethod method;
  FaceReply (*run)(HapticService&, std::string_view, Codec, CallContext&);
};

const std::vector<Entry>& entries() {
#define HAPTIC_JSON_UNARY(name, Request, Response)                                             \
  Entry{{#name, v1::Request::descriptor(), v1::Response::descriptor()},                        \
        &run<v1::Request, v1::Response, &HapticService::name>},
  static const std::vector<Entry> table{HAPTIC_V1_UNARY_RPCS(HAPTIC_JSON_UNARY)};
#undef HAPTIC_JSON_UNARY
  return table;
}

/// The length of the well-formed UTF-8 sequence at `text[i]` (1 to 4), or 0 when there is none.
std::size_t utf8_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  // The sequence's length, and the least code point it may write (shorter is overlong).
  std::size_t length = 0;
  std::uint32_t least = 0;
  if (lead >= 0xc2 && lead <= 0xdf) {
    length = 2;
    least = 0x80;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    least = 0x800;
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    least = 0x10000;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  std::uint32_t point = lead & (0x7f >> length);
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xc0) != 0x80) return 0;
    point = (point << 6) | (byte(i + k) & 0x3f);
  }
  const bool surrogate = point >= 0xd800 && point <= 0xdfff;
  return point >= least && point <= 0x10ffff && !surrogate ? length : 0;
}

/// A string's characters as JSON writes them inside quotes. A byte that is not part of
/// well-formed UTF-8 becomes U+FFFD, so that the body is JSON whatever a message holds.
std::string json_escaped(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size() + 8);
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x80) {
      const std::size_t length = utf8_length(text, i);
      if (length == 0) {
        out += "\\ufffd";
        ++i;
      } else {
        out.append(text.substr(i, length));
        i += length;
      }
      continue;
    }
    ++i;
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          out += "\\u00";
          out += kHex[c >> 4];
          out += kHex[c & 0xf];
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out;
}

}  // namespace

FaceReply JsonFace::call(std::string_view method, std::string_view body, BodyCodec codec,
                         CallContext& context) const {
  for (const Entry& entry : entries()) {
    if (entry.method.name != method) continue;
    try {
      return entry.run(service_, body, codec, context);
    } catch (const std::exception& error) {
      return error_reply({grpc::StatusCode::INTERNAL, std::string(method) + ": " + error.what()});
    } catch (...) {
      return error_reply({grpc::StatusCode::INTERNAL, std::string(method) + ": an unknown error"});
    }
  }
  if (method == "WatchEvents") {
    return error_reply({grpc::StatusCode::UNIMPLEMENTED,
                        "WatchEvents is a stream: open it as a WebSocket at " +
                            std::string(kPathPrefix) + "WatchEvents (docs/http.md)"});
  }
  return error_reply({grpc::StatusCode::UNIMPLEMENTED,
                      "haptic.v1.Haptic has no call '" + std::string(method) + "'"});
}

std::vector<FaceMethod> JsonFace::methods() {
  std::vector<FaceMethod> out;
  for (const Entry& entry : entries()) out.push_back(entry.method);
  return out;
}

std::string_view code_name(grpc::StatusCode code) {
  // Indexed by gRPC's code number, 0 to 16.
  static constexpr std::array<std::string_view, 17> kNames{
      "ok",        "canceled",          "unknown",           "invalid_argument",
      "deadline_exceeded", "not_found", "already_exists",    "permission_denied",
      "resource_exhausted", "failed_precondition", "aborted", "out_of_range",
      "unimplemented", "internal",      "unavailable",       "data_loss",
      "unauthenticated"};
  const auto index = static_cast<std::size_t>(code);
  return index < kNames.size() ? kNames[index] : "unknown";
}

int http_status_of(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return 200;
    case grpc::StatusCode::CANCELLED: return 499;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::OUT_OF_RANGE: return 400;
    case grpc::StatusCode::DEADLINE_EXCEEDED: return 504;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::ABORTED: return 409;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNIMPLEMENTED: return 501;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    default: return 500;
  }
}

FaceReply error_reply(const grpc::Status& status) {
  FaceReply reply;
  reply.code = status.error_code();
  reply.http_status = http_status_of(status.error_code());
  reply.content_type = "application/json";
  reply.body = "{\"code\":\"" + std::string(code_name(status.error_code())) + "\",\"message\":\"" +
               json_escaped(status.error_message()) + "\"}";
  return reply;
}

}  // namespace haptic::net
