// ServerConfig.security: what a token must be, what a non-loopback address needs, and errors
// that name the field and the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "config/security.hpp"
#include "config/server_config.hpp"
#include "haptic/io/bounded_file.hpp"
#include "parse_error.hpp"

namespace haptic::config {
namespace {

constexpr const char* kTls = R"("tls": {"cert_file": "server.pem", "key_file": "server.key"})";
constexpr const char* kToken =
    R"("tokens": [{"name": "alice", "token": "0123456789abcdef0123", "role": "CONTROLLER"}])";

TEST(SecurityConfig, ANonLoopbackAddressNeedsTlsAndTokensOrInsecure) {
  const std::string address = R"("grpc_address": "0.0.0.0:50051", "udp_address": "0.0.0.0", )";
  EXPECT_EQ(error_of("{" + address + R"("security": {)" + kTls + ", " + kToken + "}}"), "");
  EXPECT_NE(error_of("{" + address + R"("security": {)" + kTls + "}}").find("security has TLS but no tokens"),
            std::string::npos);
  EXPECT_NE(error_of("{" + address + R"("security": {)" + kToken + "}}").find("security has tokens but no TLS"),
            std::string::npos);
  EXPECT_NE(error_of("{" + address + "\"max_sessions\": 4}").find("security has neither TLS nor tokens"),
            std::string::npos);
  EXPECT_EQ(error_of("{" + address + "\"insecure_remote_access\": true}"), "");
  // A tokens file counts as tokens.
  EXPECT_EQ(error_of("{" + address + R"("security": {)" + kTls + R"(, "tokens_file": "t.json"}})"), "");
}

TEST(SecurityConfig, EveryTokenFieldIsChecked) {
  const auto token_error = [](const std::string& token) {
    return error_of(R"({"security": {"tokens": [)" + token + "]}}");
  };
  EXPECT_NE(token_error(R"({"name": "a", "token": "short", "role": "ADMIN"})")
                .find("security.tokens[0].token: must be 16 to 256 printable characters"),
            std::string::npos);
  EXPECT_NE(token_error(R"({"name": "a", "token": "has a space in it ok", "role": "ADMIN"})")
                .find("security.tokens[0].token"),
            std::string::npos);
  EXPECT_NE(token_error(R"({"name": "", "token": "0123456789abcdef", "role": "ADMIN"})")
                .find("security.tokens[0].name"),
            std::string::npos);
  EXPECT_NE(token_error(R"({"name": "a", "token": "0123456789abcdef"})").find("security.tokens[0].role"),
            std::string::npos);
  EXPECT_NE(token_error(R"({"name": "a", "token": "0123456789abcdef", "role": "ADMIN"},
                           {"name": "a", "token": "fedcba9876543210", "role": "OBSERVER"})")
                .find("security.tokens[1].name: 'a' is given twice"),
            std::string::npos);
  EXPECT_NE(token_error(R"({"name": "a", "token": "0123456789abcdef", "role": "ADMIN"},
                           {"name": "b", "token": "0123456789abcdef", "role": "OBSERVER"})")
                .find("security.tokens[1].token: 'b' has the same secret as token 'a'; each token needs its own"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"security": {"tls": {"key_file": "k.pem"}}})").find("security.tls.cert_file: required"),
            std::string::npos);
}

TEST(SecurityConfig, LoadingNamesTheFileThatCannotBeRead) {
  v1::SecurityConfig security;
  security.mutable_tls()->set_cert_file("/nonexistent/server.pem");
  security.mutable_tls()->set_key_file("/nonexistent/server.key");
  try {
    (void)load_security(security);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("security.tls.cert_file: '/nonexistent/server.pem': cannot open: "
                                             "No such file or directory"),
              std::string::npos) << error.what();
  }
}

// A file named by mistake (a device, a log) is refused at its bound, naming it, not read until
// memory runs out: /dev/zero never ends.
TEST(SecurityConfig, AFileWithoutEndIsRefusedAtItsBoundNamingIt) {
  v1::SecurityConfig security;
  security.mutable_tls()->set_cert_file("/dev/zero");
  security.mutable_tls()->set_key_file("/dev/zero");
  try {
    (void)load_security(security);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()),
              "security.tls.cert_file: '/dev/zero': larger than 1 MiB, the most read for a tokens or PEM file");
  }
  std::string text;
  EXPECT_EQ(io::read_bounded_file("/dev/zero", 4096, "a test file", text),
            "'/dev/zero': larger than 0 MiB, the most read for a test file");
  EXPECT_TRUE(text.empty());
  EXPECT_EQ(io::read_bounded_file("/nonexistent/x", 4096, "a test file", text),
            "'/nonexistent/x': cannot open: No such file or directory");
  // `hapticd --config /dev/zero` once read 1.2 GB in 5 s.
  try {
    (void)load_config_file("/dev/zero");
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_EQ(std::string(error.what()),
              "--config '/dev/zero': larger than 256 MiB, the most read for a configuration file");
  }
}

TEST(SecurityConfig, ATokensFileJoinsTheInlineTokensAndIsValidatedWithThem) {
  const auto dir = std::filesystem::temp_directory_path() / ("hapticd-security-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = (dir / "tokens.json").string();
  std::ofstream(path) << R"({"tokens": [{"name": "bob", "token": "fedcba9876543210", "role": "OBSERVER",
                                         "expires": "2030-01-01T00:00:00Z"}]})";
  v1::SecurityConfig security;
  v1::AccessToken& alice = *security.add_tokens();
  alice.set_name("alice");
  alice.set_token("0123456789abcdef");
  alice.set_role(v1::ADMIN);
  security.set_tokens_file(path);
  const SecurityMaterial material = load_security(security);
  ASSERT_EQ(material.tokens.tokens_size(), 2);
  EXPECT_EQ(material.tokens.tokens(1).name(), "bob");
  EXPECT_EQ(material.tokens.tokens(1).expires().seconds(), 1893456000);
  EXPECT_FALSE(material.tls);

  std::ofstream(path) << R"({"tokens": [{"name": "alice", "token": "fedcba9876543210", "role": "OBSERVER"}]})";
  try {
    (void)load_security(security);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("tokens[1].name: 'alice' is given twice"), std::string::npos)
        << error.what();
  }
  std::ofstream(path) << R"({"tokens": [{"name": "x", "secret": "nope"}]})";
  try {
    (void)load_security(security);
    FAIL() << "no error";
  } catch (const ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("security.tokens_file '" + path + "': not valid AccessTokens JSON"),
              std::string::npos) << error.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace haptic::config
