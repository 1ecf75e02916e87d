// Every way a TLS connection goes wrong gets one line naming the cause and the option that fixes
// it, from the tools a user types (hapticctl, touch_wall, hapticd --health-check): an expired or
// not yet valid certificate on either side, a client certificate from another CA, none where one
// is asked for, a name the server's certificate lacks, a CA that did not sign it, and plaintext
// against TLS both ways. gRPC alone says "Connection reset by peer" or "Endpoint read failed" for
// most of them, and its own log lines ("E1205 ... Handshake failed") do not reach the terminal.

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "integration/run_program.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {
namespace {

const std::string kCerts = TEST_CERTS_DIR;

/// A lockstep server with TLS from `certificate` (in the test CA's folder); `mutual` asks clients
/// for a certificate the test CA signed.
std::string tls_config(const std::string& certificate, bool mutual) {
  std::string tls = R"("cert_file": ")" + kCerts + "/" + certificate + R"(", "key_file": ")" + kCerts +
                    "/server.key\"";
  if (mutual) tls += R"(, "client_ca_file": ")" + kCerts + "/ca.pem\"";
  return R"({"time_mode": "LOCKSTEP", "security": {"tls": {)" + tls + "}}}";
}

std::string address_of(const ServerProcess& server) { return "127.0.0.1:" + std::to_string(server.grpc_port()); }

/// The servers every case below dials, started once.
class TlsErrors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mutual_ = std::make_unique<ServerProcess>(tls_config("server.pem", true));
    expired_ = std::make_unique<ServerProcess>(tls_config("server_expired.pem", false));
    future_ = std::make_unique<ServerProcess>(tls_config("server_future.pem", false));
    plaintext_ = std::make_unique<ServerProcess>(R"({"time_mode": "LOCKSTEP"})");
  }
  static void TearDownTestSuite() {
    mutual_.reset();
    expired_.reset();
    future_.reset();
    plaintext_.reset();
  }

  /// hapticctl status against `server` with `options`: it must fail with exactly one line, holding
  /// every one of `expected`.
  static void expect_one_line(const std::vector<std::string>& arguments, const std::vector<std::string>& expected,
                              const std::string& binary = HAPTICCTL_BINARY) {
    const Outcome outcome = run_program(binary, arguments);
    EXPECT_EQ(outcome.exit_code, 1) << outcome.output;
    EXPECT_EQ(std::count(outcome.output.begin(), outcome.output.end(), '\n'), 1)
        << "not one line (gRPC's own log lines?):\n" << outcome.output;
    for (const std::string& part : expected) {
      EXPECT_NE(outcome.output.find(part), std::string::npos) << "no '" << part << "' in:\n" << outcome.output;
    }
  }
  static std::vector<std::string> hapticctl(const ServerProcess& server, std::vector<std::string> options) {
    options.insert(options.begin(), {"--server", address_of(server)});
    options.push_back("status");
    return options;
  }

  static inline std::unique_ptr<ServerProcess> mutual_, expired_, future_, plaintext_;
};

TEST_F(TlsErrors, AnExpiredClientCertificateIsNamedWithItsDate) {
  expect_one_line(hapticctl(*mutual_, {"--ca", kCerts + "/ca.pem", "--cert", kCerts + "/client_expired.pem",
                                       "--key", kCerts + "/client.key"}),
                  {"the client certificate in tls.cert_file (--cert) '" + kCerts + "/client_expired.pem'",
                   "expired on 2020-02-01 00:00:00 UTC", "give a current one"});
}

TEST_F(TlsErrors, AClientCertificateNotYetValidIsNamedWithItsDateAndTheClock) {
  expect_one_line(hapticctl(*mutual_, {"--ca", kCerts + "/ca.pem", "--cert", kCerts + "/client_future.pem",
                                       "--key", kCerts + "/client.key"}),
                  {"client_future.pem' is not valid before 2099-01-01 00:00:00 UTC", "this host's clock says"});
}

// The server refuses it after the handshake, and gRPC often closes without the alert: the line
// must come every time, not now and then.
TEST_F(TlsErrors, AClientCertificateFromAnotherCaIsRefusedNamingItsIssuerEveryTime) {
  for (int attempt = 0; attempt < 5; ++attempt) {
    expect_one_line(hapticctl(*mutual_, {"--ca", kCerts + "/ca.pem", "--cert", kCerts + "/client_other_ca.pem",
                                         "--key", kCerts + "/client.key"}),
                    {"the server refuses the client certificate in tls.cert_file (--cert)",
                     "signed by 'CN=another CA'", "security.tls.client_ca_file"});
  }
}

TEST_F(TlsErrors, NoClientCertificateWhereOneIsAskedForNamesCertAndKey) {
  expect_one_line(hapticctl(*mutual_, {"--ca", kCerts + "/ca.pem"}),
                  {"the server asks for a client certificate (mutual TLS)", "tls.cert_file (--cert)",
                   "tls.key_file (--key)"});
}

TEST_F(TlsErrors, ANameTheServersCertificateLacksListsTheNamesItCarriesAndNamesServerName) {
  expect_one_line(hapticctl(*mutual_, {"--ca", kCerts + "/ca.pem", "--cert", kCerts + "/client.pem", "--key",
                                       kCerts + "/client.key", "--server-name", "haptics.other.lab"}),
                  {"the server's certificate carries localhost, 127.0.0.1, 10.79.0.1, not 'haptics.other.lab'",
                   "--server-name"});
}

TEST_F(TlsErrors, AnExpiredServerCertificateIsTheOperatorsToRenew) {
  expect_one_line(hapticctl(*expired_, {"--ca", kCerts + "/ca.pem"}),
                  {"the server's certificate expired on 2020-02-01 00:00:00 UTC", "its operator must renew it"});
}

TEST_F(TlsErrors, AServerCertificateNotYetValidPointsAtTheClocks) {
  expect_one_line(hapticctl(*future_, {"--ca", kCerts + "/ca.pem"}),
                  {"the server's certificate is not valid before 2099-01-01 00:00:00 UTC", "set the clock right"});
}

TEST_F(TlsErrors, ACaThatDidNotSignTheServersCertificateIsNamedWithTheOneThatDid) {
  expect_one_line(hapticctl(*future_, {"--ca", kCerts + "/other_ca.pem"}),
                  {"the server's certificate is signed by 'CN=hapticd test CA'",
                   "tls.ca_file (--ca) '" + kCerts + "/other_ca.pem' (which holds 'CN=another CA')"});
}

TEST_F(TlsErrors, PlaintextAgainstTlsAndTlsAgainstPlaintextEachNameTheFix) {
  expect_one_line(hapticctl(*expired_, {}), {"the server speaks TLS", "(--ca)"});
  expect_one_line(hapticctl(*mutual_, {}), {"the server speaks TLS", "it asks for one (mutual TLS)"});
  expect_one_line(hapticctl(*plaintext_, {"--ca", kCerts + "/ca.pem"}),
                  {"the server does not speak TLS", "leave out --ca"});
}

// touch_wall used to answer a TLS refusal with "Start it with ./scripts/run": starting a server is
// the fix only where nothing listens.
TEST_F(TlsErrors, TouchWallSuggestsStartingAServerOnlyWhereNothingListens) {
  const Outcome refused = run_program(TOUCH_WALL_BINARY, {address_of(*mutual_), "--lockstep"});
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("the server speaks TLS"), std::string::npos) << refused.output;
  EXPECT_EQ(refused.output.find("./scripts/run"), std::string::npos) << refused.output;
  EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;

  ServerProcess gone(R"({"time_mode": "LOCKSTEP"})");
  const std::string address = address_of(gone);
  gone.stop();
  const Outcome nobody = run_program(TOUCH_WALL_BINARY, {address, "--lockstep"});
  EXPECT_EQ(nobody.exit_code, 1) << nobody.output;
  EXPECT_NE(nobody.output.find("nothing listens there"), std::string::npos) << nobody.output;
  EXPECT_NE(nobody.output.find("Start one with ./scripts/run"), std::string::npos) << nobody.output;
}

TEST_F(TlsErrors, TheHealthCheckNamesItsOwnOptions) {
  expect_one_line({"--health-check", address_of(*mutual_)}, {"the server speaks TLS", "--health-ca"},
                  HAPTICD_BINARY);
  expect_one_line({"--health-check", address_of(*mutual_), "--health-ca", kCerts + "/ca.pem"},
                  {"the server asks for a client certificate", "--health-cert", "--health-key"}, HAPTICD_BINARY);
  expect_one_line({"--health-check", address_of(*expired_), "--health-ca", kCerts + "/ca.pem"},
                  {"the server's certificate expired on 2020-02-01"}, HAPTICD_BINARY);
  expect_one_line({"--health-check", address_of(*plaintext_), "--health-ca", kCerts + "/ca.pem"},
                  {"the server does not speak TLS", "leave out --health-ca"}, HAPTICD_BINARY);
  const Outcome serving = run_program(HAPTICD_BINARY, {"--health-check", address_of(*mutual_), "--health-ca",
                                                       kCerts + "/ca.pem", "--health-cert", kCerts + "/client.pem",
                                                       "--health-key", kCerts + "/client.key"});
  EXPECT_EQ(serving.exit_code, 0) << serving.output;
}

}  // namespace
}  // namespace haptic::test
