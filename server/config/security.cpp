#include "config/security.hpp"

#include <google/protobuf/util/json_util.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "config/server_config.hpp"
#include "haptic/io/bounded_file.hpp"

namespace haptic::config {
namespace {

constexpr std::size_t kMinTokenLength = 16;
constexpr std::size_t kMaxTokenLength = 256;
constexpr std::size_t kMaxTokenNameLength = 64;

bool printable(const std::string& text, bool spaces_allowed) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (!std::isprint(u) || (!spaces_allowed && u == ' ')) return false;
  }
  return true;
}

/// Empty when every token is valid and none repeats another's name or secret.
std::string validate_tokens(const v1::AccessTokens& tokens, const std::string& prefix) {
  std::set<std::string> names;
  std::map<std::string, std::string> secrets;  // each secret, and the name of the token holding it
  for (int i = 0; i < tokens.tokens_size(); ++i) {
    const v1::AccessToken& token = tokens.tokens(i);
    const std::string at = prefix + "tokens[" + std::to_string(i) + "].";
    if (token.name().empty() || token.name().size() > kMaxTokenNameLength ||
        !printable(token.name(), true)) {
      return at + "name: must be 1 to 64 printable characters";
    }
    if (token.token().size() < kMinTokenLength || token.token().size() > kMaxTokenLength ||
        !printable(token.token(), false)) {
      return at + "token: must be 16 to 256 printable characters without spaces (got " +
             std::to_string(token.token().size()) + "); `openssl rand -hex 32` makes one";
    }
    if (token.role() != v1::OBSERVER && token.role() != v1::CONTROLLER && token.role() != v1::ADMIN) {
      return at + "role: must be OBSERVER, CONTROLLER or ADMIN";
    }
    if (token.has_expires() && (token.expires().seconds() < 0 || token.expires().nanos() < 0)) {
      return at + "expires: must be after 1970-01-01T00:00:00Z";
    }
    if (!names.insert(token.name()).second) return at + "name: '" + token.name() + "' is given twice";
    if (const auto [earlier, fresh] = secrets.emplace(token.token(), token.name()); !fresh) {
      return at + "token: '" + token.name() + "' has the same secret as token '" + earlier->second +
             "'; each token needs its own";
    }
  }
  return {};
}

std::string read_file(const std::string& field, const std::string& path) {
  std::string text;
  if (std::string error = io::read_bounded_file(path, io::kMaxSecretFileBytes, "a tokens or PEM file", text);
      !error.empty()) {
    throw ConfigError("security." + field + ": " + error);
  }
  if (text.empty()) throw ConfigError("security." + field + ": '" + path + "' is empty");
  return text;
}

}  // namespace

std::string validate_security(const v1::SecurityConfig& security) {
  if (security.has_tls()) {
    if (security.tls().cert_file().empty()) return "security.tls.cert_file: required with tls";
    if (security.tls().key_file().empty()) return "security.tls.key_file: required with tls";
  }
  v1::AccessTokens inline_tokens;
  *inline_tokens.mutable_tokens() = security.tokens();
  return validate_tokens(inline_tokens, "security.");
}

bool secured_for_remote_access(const v1::SecurityConfig& security) {
  return security.has_tls() && (security.tokens_size() > 0 || !security.tokens_file().empty());
}

SecurityMaterial load_security(const v1::SecurityConfig& security) {
  SecurityMaterial material;
  if (security.has_tls()) {
    material.tls = true;
    material.cert_pem = read_file("tls.cert_file", security.tls().cert_file());
    material.key_pem = read_file("tls.key_file", security.tls().key_file());
    if (!security.tls().client_ca_file().empty()) {
      material.client_ca_pem = read_file("tls.client_ca_file", security.tls().client_ca_file());
    }
  }
  *material.tokens.mutable_tokens() = security.tokens();
  if (!security.tokens_file().empty()) {
    const std::string where = "security.tokens_file '" + security.tokens_file() + "'";
    v1::AccessTokens from_file;
    google::protobuf::util::JsonParseOptions options;
    options.ignore_unknown_fields = false;
    const auto status = google::protobuf::util::JsonStringToMessage(
        read_file("tokens_file", security.tokens_file()), &from_file, options);
    if (!status.ok()) {
      throw ConfigError(where + ": not valid AccessTokens JSON: " + std::string(status.message()));
    }
    if (from_file.tokens_size() == 0) throw ConfigError(where + ": holds no tokens");
    for (const v1::AccessToken& token : from_file.tokens()) *material.tokens.add_tokens() = token;
  }
  if (auto error = validate_tokens(material.tokens, ""); !error.empty()) {
    throw ConfigError("security (tokens and tokens_file together): " + error);
  }
  return material;
}

}  // namespace haptic::config
