#include "net/http_face.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <utility>

#include <google/protobuf/struct.pb.h>

#include "haptic/io/session_secret.hpp"
#include "net/access_control.hpp"
#include "net/proto_json.hpp"

namespace haptic::net {
namespace {

constexpr const char* kCorsAllowedHeaders =
    "authorization, content-type, haptic-session-secret-bin, connect-protocol-version, "
    "connect-timeout-ms";

/// A call that came over HTTP, as the service sees it: the peer, the metadata the face found
/// beside the headers (decoded "-bin" headers; a stream's opening's credentials), the headers, and
/// for a stream whether its WebSocket is still open.
class FaceCall final : public CallContext {
 public:
  FaceCall(const HttpRequest& request, std::vector<std::pair<std::string, std::string>> metadata,
           const WebSocketChannel* stream = nullptr)
      : request_(request), metadata_(std::move(metadata)), stream_(stream) {}

  std::string peer_host() const override { return request_.peer; }

  std::optional<std::string> metadata(std::string_view key) const override {
    for (const auto& [name, value] : metadata_) {
      if (name == key) return value;
    }
    const std::string* value = request_.header(std::string(key));
    if (value == nullptr) return std::nullopt;
    return *value;
  }

  /// A unary call ends with its reply; a stream, when its WebSocket closes.
  bool cancelled() const override { return stream_ != nullptr && stream_->closed(); }

 private:
  const HttpRequest& request_;
  std::vector<std::pair<std::string, std::string>> metadata_;
  const WebSocketChannel* stream_;
};

/// The request's "-bin" headers decoded from base64 (as gRPC decodes its binary metadata) onto
/// `out`; "" or what is wrong.
std::string decode_binary_headers(const HttpRequest& request, std::vector<std::pair<std::string, std::string>>& out) {
  for (const auto& [name, value] : request.headers) {
    if (name.size() <= 4 || name.compare(name.size() - 4, 4, "-bin") != 0) continue;
    std::string bytes;
    if (!decode_base64(value, bytes)) return name + ": must be base64 (a binary header, as in gRPC)";
    out.emplace_back(name, std::move(bytes));
  }
  return {};
}

/// Events as text messages, {"event": {...}}.
class EventMessages final : public StreamWriter<v1::Event> {
 public:
  explicit EventMessages(WebSocketChannel& channel) : channel_(channel) {}
  bool write(const v1::Event& event) override { return channel_.send("{\"event\": " + to_json(event) + "}", false); }

 private:
  WebSocketChannel& channel_;
};

/// State datagrams as binary messages.
class DatagramMessages final : public StreamWriter<std::string> {
 public:
  explicit DatagramMessages(WebSocketChannel& channel) : channel_(channel) {}
  bool write(const std::string& datagram) override { return channel_.send(datagram, true); }

 private:
  WebSocketChannel& channel_;
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

StreamOpening read_opening(const std::string& message) {
  StreamOpening opening;
  google::protobuf::Struct parsed;
  if (const std::string error = from_json(message, parsed); !error.empty()) {
    opening.error = "the opening message is not a JSON object: " + error;
    return opening;
  }
  for (const auto& [name, value] : parsed.fields()) {
    if (name == "request") {
      if (!value.has_struct_value()) {
        opening.error = "request: must be an object";
        return opening;
      }
      opening.request = to_json(value.struct_value());
    } else if (name == "authorization" && value.has_string_value()) {
      opening.authorization = value.string_value();
    } else if (name == "session_secret" && value.has_string_value()) {
      std::string bytes;
      if (!decode_base64(value.string_value(), bytes)) {
        opening.error = "session_secret: must be base64, as OpenSession's reply writes it";
        return opening;
      }
      opening.session_secret = std::move(bytes);
    } else {
      opening.error = "the opening message has '" + name.substr(0, 100) +
                      "': it takes request (an object), authorization and session_secret (strings)";
      return opening;
    }
  }
  if (opening.request.empty()) opening.error = "the opening message has no request";
  return opening;
}

std::string encode_base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t left = bytes.size() - i;
    std::uint32_t group = static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])) << 16;
    if (left > 1) group |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 8;
    if (left > 2) group |= static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(group >> 18) & 63];
    out += kAlphabet[(group >> 12) & 63];
    out += left > 1 ? kAlphabet[(group >> 6) & 63] : '=';
    out += left > 2 ? kAlphabet[group & 63] : '=';
  }
  return out;
}

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
    : service_(service), face_(service), options_(std::move(options)), http_("http", options_.limits) {}

void HttpFace::start() {
  http_.serve_websockets([this](const HttpRequest& request) { return check_upgrade(request); },
                         [this](const HttpRequest& request, WebSocketChannel& channel) { stream(request, channel); });
  http_.start([this](const HttpRequest& request) { return handle(request); });
}

std::optional<HttpResponse> HttpFace::origin_refusal(const HttpRequest& request) const {
  const std::string* origin = request.header("origin");
  if (origin == nullptr || std::find(options_.allowed_origins.begin(), options_.allowed_origins.end(),
                                     *origin) != options_.allowed_origins.end()) {
    return std::nullopt;
  }
  return error_response(grpc::StatusCode::PERMISSION_DENIED,
                        "origin '" + origin->substr(0, 200) +
                            "' may not call this server: it is not in http_allowed_origins");
}

std::optional<HttpResponse> HttpFace::check_upgrade(const HttpRequest& request) const {
  if (auto refusal = origin_refusal(request)) return refusal;
  if (request.path != std::string(JsonFace::kPathPrefix) + "WatchEvents" &&
      request.path != std::string(JsonFace::kPathPrefix) + "StreamState") {
    return error_response(grpc::StatusCode::NOT_FOUND,
                          "no stream at '" + request.path.substr(0, 200) + "': the streams are " +
                              std::string(JsonFace::kPathPrefix) + "WatchEvents and " +
                              std::string(JsonFace::kPathPrefix) + "StreamState (docs/http.md)");
  }
  return std::nullopt;
}

void HttpFace::stream(const HttpRequest& request, WebSocketChannel& channel) const {
  const auto refuse = [&channel](const grpc::Status& status) {
    channel.send("{\"error\": " + error_reply(status).body + "}", false);
    channel.close(1008, std::string(code_name(status.error_code())));
  };
  const std::optional<std::string> first = channel.receive(options_.limits.timeout);
  if (!first) {
    refuse({grpc::StatusCode::DEADLINE_EXCEEDED,
            "no opening message within " + std::to_string(options_.limits.timeout.count()) +
                " ms: send {\"request\": {...}} first (docs/http.md)"});
    return;
  }
  StreamOpening opening = read_opening(*first);
  if (!opening.error.empty()) {
    refuse({grpc::StatusCode::INVALID_ARGUMENT, opening.error});
    return;
  }
  // Credentials from the opening message, else from the upgrade's headers.
  std::vector<std::pair<std::string, std::string>> metadata;
  if (opening.authorization) metadata.emplace_back(kAuthorizationMetadataKey, *opening.authorization);
  if (opening.session_secret) metadata.emplace_back(io::kSessionSecretMetadataKey, *opening.session_secret);
  // The upgrade's "-bin" headers after the opening's credentials: those win.
  if (const std::string error = decode_binary_headers(request, metadata); !error.empty()) {
    refuse({grpc::StatusCode::INVALID_ARGUMENT, error});
    return;
  }
  FaceCall call(request, std::move(metadata), &channel);
  // The opening's request, as the stream's message type; false (refused, saying why) when it is not one.
  const auto read_request = [&](google::protobuf::Message& message) {
    const std::string error = from_json(opening.request, message);
    if (!error.empty()) refuse({grpc::StatusCode::INVALID_ARGUMENT, "request: " + error});
    return error.empty();
  };
  grpc::Status status;
  if (request.path.ends_with("WatchEvents")) {
    v1::WatchEventsRequest watch;
    if (!read_request(watch)) return;
    EventMessages events(channel);
    status = service_.WatchEvents(&call, &watch, &events);
  } else {
    v1::StreamStateRequest state;
    if (!read_request(state)) return;
    DatagramMessages datagrams(channel);
    status = service_.StreamState(&call, &state, &datagrams);
  }
  if (!status.ok()) {
    refuse(status);
    return;
  }
  channel.close(1000, "the stream has ended");
}

HttpResponse HttpFace::handle(const HttpRequest& request) const {
  // A browser says whose page sends the request; only the allowed origins' pages are served.
  if (auto refusal = origin_refusal(request)) return std::move(*refusal);
  const std::string* origin = request.header("origin");  // past the refusal: an allowed one, if any
  const auto with_cors = [origin](HttpResponse response) {
    if (origin != nullptr) {
      response.headers.emplace_back("Access-Control-Allow-Origin", *origin);
      response.headers.emplace_back("Vary", "Origin");
    }
    return response;
  };
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
  if (const std::string error = decode_binary_headers(request, decoded); !error.empty()) {
    return with_cors(error_response(grpc::StatusCode::INVALID_ARGUMENT, error));
  }
  FaceCall call(request, std::move(decoded));
  return with_cors(from_reply(face_.call(method, request.body, codec, call)));
}

}  // namespace haptic::net
