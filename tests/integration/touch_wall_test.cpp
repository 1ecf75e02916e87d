// The tour's example as a lab runs it first: touch_wall against a secured server (TLS, mutual
// TLS, a token) prints what it prints against a plain one; against a device with no simulated
// hand (the example driver, whose own push stands in for a person) it renders the wall and
// prints what the tool does instead of exiting; its options are refused with status 2, naming
// what was wrong.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "integration/run_program.hpp"
#include "integration/server_process.hpp"
#include "integration/touch_wall_output.hpp"

namespace haptic::test {
namespace {

const std::string kCerts = TEST_CERTS_DIR;
constexpr const char* kToken = "lab-controller-token-0123456789";

Outcome touch_wall(const std::vector<std::string>& args) { return run_program(TOUCH_WALL_BINARY, args); }

/// The table rows of touch_wall's output (lines that start with a time), without the header.
std::string rows_of(const std::string& output) {
  std::istringstream lines(output);
  std::string out;
  for (std::string line; std::getline(lines, line);) {
    if (line.size() > 7 && line[3] == '.' && line.find("touch_wall") == std::string::npos) out += line + "\n";
  }
  return out;
}

TEST(TouchWall, OnASecuredServerItPrintsWhatItPrintsOnAPlainOne) {
  ServerProcess plain(lockstep_config());
  const Outcome reference = touch_wall({plain.address(), "--lockstep"});
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  ASSERT_GT(rows_of(reference.output).size(), 1000u) << reference.output;

  ServerProcess secured(lockstep_config(
      R"("security": {"tls": {"cert_file": ")" + kCerts + R"(/server.pem", "key_file": ")" + kCerts +
      R"(/server.key", "client_ca_file": ")" + kCerts + R"(/ca.pem"}, "tokens": [{"name": "lab",
      "token": ")" + kToken + R"(", "role": "CONTROLLER"}]})"));
  const Outcome secure = touch_wall({secured.address(), "--lockstep", "--token", kToken, "--ca",
                                     kCerts + "/ca.pem", "--cert", kCerts + "/client.pem", "--key",
                                     kCerts + "/client.key"});
  ASSERT_EQ(secure.exit_code, 0) << secure.output;
  EXPECT_EQ(rows_of(secure.output), rows_of(reference.output));

  // Without the client certificate: refused, saying what to give.
  const Outcome no_cert = touch_wall({secured.address(), "--lockstep", "--token", kToken, "--ca",
                                      kCerts + "/ca.pem"});
  EXPECT_EQ(no_cert.exit_code, 1) << no_cert.output;
  EXPECT_NE(no_cert.output.find("asks for a client certificate"), std::string::npos) << no_cert.output;
}

TEST(TouchWall, OnADeviceWithoutASimulatedHandItRendersTheWallAndPrintsWhatTheToolDoes) {
  // The example driver pushes the tool down with 1 N from 10 mm above the wall: at rest it sits
  // 1 mm in (1 N over touch_wall's 1000 N/m).
  ServerProcess server(R"({"time_mode": "LOCKSTEP", "udp_address": "127.0.0.1", "status_period_s": 0,
      "real_time": {"use_fifo": false},
      "driver": {"library": ")" POINT_MASS_DRIVER R"(", "call_timeout_ms": 5000,
                 "params": {"initial": [0, 0, 0.01],
                 "push": [0, 0, -1], "mass": 0.05, "damping": 0.5}}})");
  const Outcome outcome = touch_wall({server.address(), "--lockstep", "--seconds", "2"});
  ASSERT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("no simulated hand; wall z < 0 with K = 1000 N/m"), std::string::npos)
      << outcome.output;
  const std::string rows = rows_of(outcome.output);
  EXPECT_NE(rows.find("yes"), std::string::npos) << "the tool reaches the wall\n" << rows;
  // The last row: at rest 1 mm in, pushed back with the driver's 1 N.
  const std::string last = rows.substr(rows.rfind('\n', rows.size() - 2) + 1);
  double t = 0, z_mm = 0, force_n = 0;
  char target[8] = {};
  ASSERT_EQ(std::sscanf(last.c_str(), "%lf %7s %lf %lf", &t, target, &z_mm, &force_n), 4) << last;
  EXPECT_NEAR(t, 2.0, 0.051);
  EXPECT_NEAR(z_mm, -1.0, 0.02);
  EXPECT_NEAR(force_n, 1.0, 0.02);
  EXPECT_NE(outcome.output.find("touch_wall: done; deepest "), std::string::npos) << outcome.output;
}

TEST(TouchWall, ItsOptionsAreRefusedWithStatusTwoNamingWhatWasWrong) {
  const Outcome cert_alone = touch_wall({"--cert", "client.pem", "--key", "client.key"});
  EXPECT_EQ(cert_alone.exit_code, 2);
  EXPECT_NE(cert_alone.output.find("--cert, --key and --server-name need --ca"), std::string::npos)
      << cert_alone.output;
  const Outcome unknown = touch_wall({"--tls"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.output.find("unknown option --tls"), std::string::npos) << unknown.output;
  const Outcome seconds = touch_wall({"--seconds", "forever"});
  EXPECT_EQ(seconds.exit_code, 2);
  // A token is never sent in clear to another host (0.0.0.0 is none of loopback's names; nothing
  // is sent: the client refuses before connecting).
  const Outcome in_clear = touch_wall({"0.0.0.0:1", "--token", kToken});
  EXPECT_EQ(in_clear.exit_code, 2);
  EXPECT_NE(in_clear.output.find("TlsOptions"), std::string::npos) << in_clear.output;
}

// The C program over the C API (examples/c/touch_wall.c) prints exactly what the C++ one prints,
// each against a fresh lockstep server: the simulated hand pressing, and the device's own hand
// watched; and it refuses the same bad options the same way.
TEST(TouchWall, TheCProgramPrintsExactlyWhatTheCppOnePrints) {
  expect_prints_what_cpp_prints(touch_wall, [](const std::vector<std::string>& args) {
    return run_program(TOUCH_WALL_C_BINARY, args);
  });
}

}  // namespace
}  // namespace haptic::test
