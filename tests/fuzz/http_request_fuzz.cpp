// Fuzz entry point: the HTTP request heads the metrics endpoint, the web viewer and the JSON face
// read from any client that reaches their port (net/http_server: Beast's parser, then hapticd's
// checks and conversion). No head may crash them; what they accept must be well formed (a
// method, a target starting with '/', its path without the query, HTTP/1.0 or 1.1, header names
// in lower case without a colon, values trimmed), and parsing must be repeatable.
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz/fuzz_seeds.hpp"
#include "net/http_server.hpp"

namespace haptic::fuzz {
std::vector<std::string> seeds() {
  return {
      "GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nAuthorization: Bearer abc\r\n",
      "HEAD /metrics?x=1 HTTP/1.0\r\nConnection: keep-alive\r\n",
      "GET / HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\nAccept: */*\r\n",
      "POST /api/scene HTTP/1.1\r\nContent-Length: 4\r\n",
  };
}
}  // namespace haptic::fuzz

namespace {

// abort() rather than assert(): the check must also hold in release builds. The line says which
// (a macro: Clang 14, which builds the fuzzers, has no std::source_location).
#define REQUIRE(condition)                                                                 \
  do {                                                                                     \
    if (!(condition)) {                                                                    \
      std::fprintf(stderr, "http_request_fuzz: the check at line %d failed\n", __LINE__); \
      std::abort();                                                                        \
    }                                                                                      \
  } while (false)

/// No optional whitespace (RFC 9110's OWS: spaces and tabs) at either end, nor a line's CR.
bool trimmed(const std::string& value) {
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  return value.empty() || (!blank(value.front()) && !blank(value.back()) && value.back() != '\r');
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace haptic::net;
  const std::string_view head(reinterpret_cast<const char*>(data), size);
  HttpRequest request;
  const std::string error = parse_request_head(head, request);
  HttpRequest again;
  REQUIRE(parse_request_head(head, again) == error);
  if (!error.empty()) return 0;

  REQUIRE(!request.method.empty() && request.method.find(' ') == std::string::npos);
  REQUIRE(!request.target.empty() && request.target.front() == '/');
  REQUIRE(request.target.find(' ') == std::string::npos);
  REQUIRE(request.target.compare(0, request.path.size(), request.path) == 0);
  REQUIRE(request.path.find('?') == std::string::npos);
  REQUIRE(request.version == "HTTP/1.1" || request.version == "HTTP/1.0");
  for (const auto& [name, value] : request.headers) {
    REQUIRE(!name.empty() && name.find(':') == std::string::npos && trimmed(name) && trimmed(value));
    for (const char c : name) REQUIRE(!std::isupper(static_cast<unsigned char>(c)));
  }
  REQUIRE(again.path == request.path && again.headers == request.headers &&
          again.keep_alive == request.keep_alive);

  return 0;
}
