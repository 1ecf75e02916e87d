// The C# client under Mono (Debian's mono-runtime, the runtime Unity's scripting grew from)
// against a real lockstep hapticd's HTTP face: the client's own checks, TLS with mutual TLS and
// tokens, the Unity package's component (with a stand-in for UnityEngine), and touch_wall in C#
// printing exactly what the C++ one prints, each against a fresh server.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "integration/recording_files.hpp"
#include "integration/run_program.hpp"
#include "integration/server_process.hpp"
#include "integration/touch_wall_output.hpp"

namespace haptic::test {
namespace {

Outcome mono(const std::string& program, const std::vector<std::string>& args) {
  std::vector<std::string> words = {"--debug", program};
  words.insert(words.end(), args.begin(), args.end());
  return run_program(MONO_BINARY, words);
}

/// A lockstep server with the HTTP face the C# client speaks to.
std::string http_lockstep_config(const std::string& extra = {}) {
  return lockstep_config(R"("http_address": "127.0.0.1:0")" + (extra.empty() ? "" : ", " + extra));
}

std::string http_address(const ServerProcess& server) {
  return "127.0.0.1:" + std::to_string(server.http_port());
}

TEST(CSharp, TheClientRegistersEveryKindHoldsAPushRefusesNamingTheFieldAndCallsBackOnItsThreads) {
  ServerProcess server(http_lockstep_config());
  const TempDir dir;
  const Outcome outcome = mono(CSHARP_TESTS, {http_address(server), dir.path()});
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("all C# checks passed"), std::string::npos) << outcome.output;
  // Its recorder's file holds every sample its callback saw (written to seen.csv), every field the
  // same, in the C++ recorder's columns.
  const auto seen = csv_rows(read_csv(dir.file("seen.csv")));
  const auto csv = csv_rows(read_csv(dir.file("session.csv")));
  EXPECT_FALSE(seen.empty());
  expect_rows_match(csv, seen, "CSV from C#");
}

TEST(CSharp, TlsMutualTlsAndTokensHoldAndEachMissingPieceIsRefusedSayingWhich) {
  const std::string certs = TEST_CERTS_RSA_DIR;
  ServerProcess server(http_lockstep_config(R"("security": {
      "tls": {"cert_file": ")" + certs + R"(/server.pem", "key_file": ")" + certs + R"(/server.key",
              "client_ca_file": ")" + certs + R"(/ca.pem"},
      "tokens": [{"name": "operator", "token": "controller-token-0123456789", "role": "CONTROLLER"}]})"));
  const Outcome outcome = mono(CSHARP_TESTS, {"--tls", "localhost:" + std::to_string(server.http_port()), certs});
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("all C# checks passed"), std::string::npos) << outcome.output;
}

TEST(CSharp, AfterAServerRestartTheClientHasANewSessionWithEveryItem) {
  auto first = std::make_unique<ServerProcess>(http_lockstep_config());
  const std::uint16_t grpc_port = first->grpc_port();
  const std::uint16_t udp_port = first->udp_port();
  const std::uint16_t http_port = first->http_port();
  const TempDir dir;
  const std::string ready = dir.file("ready");
  Outcome outcome;
  std::thread client([&] { outcome = mono(CSHARP_TESTS, {"--reconnect", http_address(*first), ready}); });
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!std::filesystem::exists(ready) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const bool was_ready = std::filesystem::exists(ready);
  first.reset();  // SIGTERM: the server ramps down and exits, every session with it
  if (was_ready) {
    // The same three ports again, as the systemd unit's Restart= brings the server back.
    ServerProcess second(lockstep_config(R"("http_address": "127.0.0.1:)" + std::to_string(http_port) + "\""),
                         {}, 0, grpc_port, udp_port);
    client.join();
  } else {
    client.join();
  }
  EXPECT_TRUE(was_ready) << outcome.output;
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("all C# checks passed"), std::string::npos) << outcome.output;
}

TEST(CSharp, TheUnityComponentMovesItsTransformWithTheTool) {
  ServerProcess server(http_lockstep_config());
  const Outcome outcome = mono(UNITY_COMPONENT_TEST, {http_address(server)});
  EXPECT_EQ(outcome.exit_code, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("the Unity component's checks passed"), std::string::npos) << outcome.output;
}

TEST(CSharp, TouchWallPrintsExactlyWhatTheCppOnePrints) {
  expect_prints_what_cpp_prints(
      [](const std::vector<std::string>& args) { return run_program(TOUCH_WALL_BINARY, args); },
      [](const std::vector<std::string>& args) { return mono(CSHARP_TOUCH_WALL, args); },
      PortSpeaks::kHttp);
}

}  // namespace
}  // namespace haptic::test
