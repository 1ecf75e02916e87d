// The tour's example as a lab runs it first: touch_wall against a secured server (TLS, mutual
// TLS, a token) prints what it prints against a plain one; against a device with no simulated
// hand (the example driver, whose own push stands in for a person) it renders the wall and
// prints what the tool does instead of exiting; its options are refused with status 2, naming
// what was wrong.

#include <gtest/gtest.h>

#include <signal.h>

#include <future>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "haptic/client.hpp"

#include "integration/run_program.hpp"
#include "integration/sdk_harness.hpp"
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

constexpr const char* kRealTime = R"({"udp_address": "127.0.0.1", "status_period_s": 0,
    "real_time": {"use_fifo": false}})";

/// Waits (up to 20 s) until `server` holds a session of touch_wall's; its id, or 0.
std::uint64_t touch_wall_session(Client& admin) {
  for (int i = 0; i < 400; ++i) {
    for (const SessionSummary& session : admin.sessions()) {
      if (session.client_name == "touch_wall") return session.session_id;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return 0;
}

// A kicked `touch_wall --hand` used to print nothing and exit 0 when its time was up.
TEST(TouchWall, KickedWhileWatchingTheHandItSaysWhyAndExitsOne) {
  for (const std::string binary : {TOUCH_WALL_BINARY, TOUCH_WALL_C_BINARY}) {
    ServerProcess server(kRealTime);
    auto run = std::async(std::launch::async, [&] {
      return run_program(binary, {server.address(), "--hand", "--seconds", "30"});
    });
    Client admin(config_for(server, "admin"));
    const std::uint64_t session = touch_wall_session(admin);
    ASSERT_NE(session, 0u) << binary;
    // Once its wall is in, touch_wall is watching (a kick before that fails its add_wall instead).
    for (int i = 0; i < 400 && admin.stats().objects == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    admin.kick_session(session, "the rig is needed elsewhere");
    ASSERT_EQ(run.wait_for(std::chrono::seconds(20)), std::future_status::ready) << binary << ": still running";
    const Outcome outcome = run.get();
    EXPECT_EQ(outcome.exit_code, 1) << binary << "\n" << outcome.output;
    EXPECT_NE(outcome.output.find("touch_wall: the server ended this session"), std::string::npos)
        << binary << "\n" << outcome.output;
    if (binary == TOUCH_WALL_BINARY) {  // the C API's connection state carries no reason
      EXPECT_NE(outcome.output.find("the rig is needed elsewhere"), std::string::npos) << outcome.output;
    }
  }
}

// After a server restart the new server's clock starts at 0 again: the rows' time used to go
// negative there. It carries on from the last row instead.
TEST(TouchWall, AcrossAServerRestartItsTimeColumnNeverGoesBack) {
  auto first = std::make_unique<ServerProcess>(kRealTime);
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  const std::string address = first->address();
  // 10 s: the restarted server's rows must come after its start and the client's reconnect, which a
  // loaded machine may take seconds over.
  auto run = std::async(std::launch::async, [&] { return touch_wall({address, "--hand", "--seconds", "10"}); });
  {
    Client admin(config_for(*first, "admin"));
    ASSERT_NE(touch_wall_session(admin), 0u);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // rows from the first server
  ::kill(first->pid(), SIGKILL);
  first->wait();
  first.reset();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ServerProcess second(kRealTime, {}, 0, grpc_port, udp_port);
  const Outcome outcome = run.get();
  ASSERT_EQ(outcome.exit_code, 0) << outcome.output;
  std::istringstream rows(rows_of(outcome.output));
  double previous = -1.0;
  int count = 0;
  for (std::string line; std::getline(rows, line); ++count) {
    const double t = std::stod(line);
    EXPECT_GE(t, previous) << "the time column went back at\n" << line << "\n" << outcome.output;
    previous = t;
  }
  EXPECT_GT(count, 20) << outcome.output;  // rows from both servers (20 a second)
  EXPECT_GT(previous, 2.5) << "no rows from the restarted server\n" << outcome.output;
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
