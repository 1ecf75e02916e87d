#include "net/http_face.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <utility>

namespace haptic::net {
namespace {

constexpr const char* kCorsAllowedHeaders =
    "authorization, content-type, haptic-session-secret-bin, connect-protocol-version, "
    "connect-timeout-ms";

/// An HTTP request as the service sees a call.
class HttpCall final : public CallContext {
 public:
  HttpCall(const HttpRequest& request, std::vector<std::pair<std::string, std::string>> decoded)
      : request_(request), decoded_(std::move(decoded)) {}

  std::string peer_host() const override { return request_.peer; }

  std::optional<std::string> metadata(std::string_view key) const override {
    for (const auto& [name, value] : decoded_) {
      if (name == key) return value;
    }
    const std::string* value = request_.header(std::string(key));
    if (value == nullptr) return std::nullopt;
    return *value;
  }

  bool cancelled() const override { return false; }  // unary: the reply is the call's end

 private:
  const HttpRequest& request_;
  std::vector<std::pair<std::string, std::string>> decoded_;  // "-bin" headers, decoded
};

HttpResponse from_reply(FaceReply reply) {
  HttpResponse response;
  response.status = reply.http_status;
  response.content_type = std::move(reply.content_type);
  response.body = std::move(reply.body);
  return response;
}

HttpResponse error_response(grpc::StatusCode code, const std::string& message) {
  return from_reply(error_reply({code, message}));
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

bool decode_base64(std::string_view text, std::string& out) {
  static constexpr auto kValues = [] {
    std::array<int, 256> values{};
    values.fill(-1);
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) values[static_cast<unsigned char>(alphabet[i])] = i;
    values['-'] = 62;  // the URL-safe alphabet
    values['_'] = 63;
    return values;
  }();
  while (!text.empty() && text.back() == '=') text.remove_suffix(1);
  if (text.size() % 4 == 1) return false;
  out.clear();
  std::uint32_t bits = 0;
  int held = 0;
  for (const char c : text) {
    const int value = kValues[static_cast<unsigned char>(c)];
    if (value < 0) return false;
    bits = (bits << 6) | static_cast<std::uint32_t>(value);
    held += 6;
    if (held >= 8) {
      held -= 8;
      out.push_back(static_cast<char>((bits >> held) & 0xff));
    }
  }
  return true;
}

HttpFace::HttpFace(HapticService& service, HttpFaceOptions options)
    : face_(service), options_(std::move(options)), http_("http", options_.limits) {}

void HttpFace::start() {
  http_.start([this](const HttpRequest& request) { return handle(request); });
}

HttpResponse HttpFace::handle(const HttpRequest& request) const {
  // A browser says whose page sends the request; only the allowed origins' pages are served.
  const std::string* origin = request.header("origin");
  const bool allowed_origin =
      origin != nullptr && std::find(options_.allowed_origins.begin(), options_.allowed_origins.end(),
                                     *origin) != options_.allowed_origins.end();
  const auto with_cors = [&](HttpResponse response) {
    if (allowed_origin) {
      response.headers.emplace_back("Access-Control-Allow-Origin", *origin);
      response.headers.emplace_back("Vary", "Origin");
    }
    return response;
  };
  if (origin != nullptr && !allowed_origin) {
    return error_response(grpc::StatusCode::PERMISSION_DENIED,
                          "origin '" + origin->substr(0, 200) +
                              "' may not call this server: it is not in http_allowed_origins");
  }
  const bool call_path = request.path.rfind(JsonFace::kPathPrefix, 0) == 0;
  if (request.method == "OPTIONS") {
    HttpResponse preflight;
    preflight.status = 204;
    preflight.headers = {{"Access-Control-Allow-Methods", "POST"},
                         {"Access-Control-Allow-Headers", kCorsAllowedHeaders},
                         {"Access-Control-Max-Age", "600"}};
    return with_cors(std::move(preflight));
  }
  if (!call_path) {
    return with_cors(error_response(grpc::StatusCode::NOT_FOUND,
                                    "no such resource '" + request.path.substr(0, 200) +
                                        "': a call is POST " + std::string(JsonFace::kPathPrefix) +
                                        "<Call> (docs/http.md)"));
  }
  const std::string method = request.path.substr(JsonFace::kPathPrefix.size());
  if (request.method != "POST") {
    HttpResponse refusal = error_response(grpc::StatusCode::UNIMPLEMENTED,
                                          request.method + " " + request.path.substr(0, 200) +
                                              ": a call is a POST with the request as its body");
    refusal.status = 405;
    refusal.headers.emplace_back("Allow", "POST");
    return with_cors(std::move(refusal));
  }
  const std::string* type_header = request.header("content-type");
  const std::string type = type_header == nullptr ? "" : lower(type_header->substr(0, type_header->find(';')));
  BodyCodec codec = BodyCodec::kJson;
  if (type == "application/proto" || type == "application/x-protobuf") {
    codec = BodyCodec::kProto;
  } else if (type != "application/json") {
    HttpResponse refusal = error_response(
        grpc::StatusCode::INVALID_ARGUMENT,
        "Content-Type: must be application/json (protobuf's JSON mapping) or application/proto, got '" +
            (type_header == nullptr ? std::string("none") : type_header->substr(0, 100)) + "'");
    refusal.status = 415;
    return with_cors(std::move(refusal));
  }
  std::vector<std::pair<std::string, std::string>> decoded;
  for (const auto& [name, value] : request.headers) {
    if (name.size() <= 4 || name.compare(name.size() - 4, 4, "-bin") != 0) continue;
    std::string bytes;
    if (!decode_base64(value, bytes)) {
      return with_cors(error_response(grpc::StatusCode::INVALID_ARGUMENT,
                                      name + ": must be base64 (a binary header, as in gRPC)"));
    }
    decoded.emplace_back(name, std::move(bytes));
  }
  HttpCall call(request, std::move(decoded));
  return with_cors(from_reply(face_.call(method, request.body, codec, call)));
}

}  // namespace haptic::net
