// hapticd's command line: what it refuses before binding anything, and the overrides it takes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "haptic/driver.h"
#include "haptic/v1/service.pb.h"
#include "haptic/version.hpp"
#include "haptic/wire/datagram.hpp"
#include "integration/run_program.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using test::Outcome;

/// Runs hapticd with `args` to completion (every call here exits at once: --print-config or a
/// refusal), capturing what it prints.
Outcome run_hapticd(const std::vector<std::string>& args) { return test::run_program(HAPTICD_BINARY, args); }

TEST(HapticdCli, ANonLoopbackAddressIsRefusedWithoutInsecureNamingTheAddress) {
  const Outcome grpc = run_hapticd({"--grpc-address", "0.0.0.0:0", "--print-config"});
  EXPECT_EQ(grpc.exit_code, 2);
  EXPECT_NE(grpc.output.find("grpc_address: '0.0.0.0:0' is not a loopback address"),
            std::string::npos)
      << grpc.output;
  const Outcome udp = run_hapticd({"--udp-address", "0.0.0.0", "--print-config"});
  EXPECT_EQ(udp.exit_code, 2);
  EXPECT_NE(udp.output.find("udp_address: '0.0.0.0' is not a loopback address"), std::string::npos)
      << udp.output;
}

TEST(HapticdCli, InsecureAcceptsRemoteAddressesAndTheOverridesReachTheConfiguration) {
  const Outcome accepted = run_hapticd(
      {"--grpc-address", "0.0.0.0:0", "--udp-address", "0.0.0.0", "--insecure", "--print-config"});
  EXPECT_EQ(accepted.exit_code, 0) << accepted.output;
  EXPECT_NE(accepted.output.find(R"("grpc_address": "0.0.0.0:0")"), std::string::npos);
  EXPECT_NE(accepted.output.find(R"("udp_address": "0.0.0.0")"), std::string::npos);
  EXPECT_NE(accepted.output.find(R"("insecure_remote_access": true)"), std::string::npos);
}

TEST(HapticdCli, InsecureOnTheCommandLineCoversARemoteAddressInTheConfigurationFile) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("hapticd-cli-remote-" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << R"({"udp_address": "0.0.0.0"})";
  const Outcome refused = run_hapticd({"--config", path.string(), "--print-config"});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find(path.string() + ": udp_address: '0.0.0.0' is not a loopback address"),
            std::string::npos)
      << refused.output;
  const Outcome accepted = run_hapticd({"--config", path.string(), "--insecure", "--print-config"});
  EXPECT_EQ(accepted.exit_code, 0) << accepted.output;
  EXPECT_NE(accepted.output.find(R"("udp_address": "0.0.0.0")"), std::string::npos);
  std::filesystem::remove(path);
}

TEST(HapticdCli, TheBuiltInDefaultsListenOnLoopbackOnly) {
  const Outcome defaults = run_hapticd({"--print-config"});
  EXPECT_EQ(defaults.exit_code, 0) << defaults.output;
  EXPECT_NE(defaults.output.find(R"("grpc_address": "127.0.0.1:50051")"), std::string::npos);
  EXPECT_NE(defaults.output.find(R"("udp_address": "127.0.0.1")"), std::string::npos);
  EXPECT_NE(defaults.output.find(R"("insecure_remote_access": false)"), std::string::npos);
}

// Two servers never share a port (no SO_REUSEPORT): clients would be split between them. The
// second one stops at start with one line naming the address and why.
TEST(HapticdCli, ASecondServerOnABusyGrpcOrUdpPortFailsAtStartWithOneClearLine) {
  test::ServerProcess first(test::lockstep_config());
  const std::string grpc = "127.0.0.1:" + std::to_string(first.grpc_port());
  const Outcome same_grpc = run_hapticd({"--lockstep", "--grpc-address", grpc, "--udp-port", "0"});
  EXPECT_EQ(same_grpc.exit_code, 1) << same_grpc.output;
  EXPECT_NE(same_grpc.output.find("cannot listen for gRPC on " + grpc + ": Address already in use"),
            std::string::npos)
      << same_grpc.output;
  const std::string udp = std::to_string(first.udp_port());
  const Outcome same_udp =
      run_hapticd({"--lockstep", "--grpc-address", "127.0.0.1:0", "--udp-port", udp});
  EXPECT_EQ(same_udp.exit_code, 1) << same_udp.output;
  EXPECT_NE(same_udp.output.find("cannot bind UDP 127.0.0.1:" + udp + ": Address already in use"),
            std::string::npos)
      << same_udp.output;
  // One line: the refusal, nothing else after the start was abandoned.
  for (const Outcome* outcome : {&same_grpc, &same_udp}) {
    EXPECT_EQ(std::count(outcome->output.begin(), outcome->output.end(), '\n'), 1) << outcome->output;
  }
  // The first server is untouched and still serves.
  EXPECT_EQ(run_hapticd({"--health-check", "127.0.0.1:" + std::to_string(first.grpc_port())}).exit_code, 0);
}

// A container's health check cannot know an ephemeral port: it finds the server through the ready
// file the server wrote.
TEST(HapticdCli, TheHealthCheckFindsTheServerThroughItsReadyFile) {
  test::ServerProcess server(test::lockstep_config());
  const Outcome check = run_hapticd({"--health-check", "--ready-file", server.ready_file()});
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find("hapticd at 127.0.0.1:" + std::to_string(server.grpc_port()) +
                              ": serving"),
            std::string::npos)
      << check.output;

  const Outcome no_file = run_hapticd({"--health-check", "--ready-file", "/nonexistent/ready.json"});
  EXPECT_EQ(no_file.exit_code, 1);
  EXPECT_NE(no_file.output.find("no ready file /nonexistent/ready.json"), std::string::npos)
      << no_file.output;
  const Outcome neither = run_hapticd({"--health-check"});
  EXPECT_EQ(neither.exit_code, 2);
  EXPECT_NE(neither.output.find("--health-check needs HOST:PORT or --ready-file"), std::string::npos)
      << neither.output;

  server.stop();
  const Outcome stopped = run_hapticd({"--health-check", "--ready-file", server.ready_file()});
  EXPECT_EQ(stopped.exit_code, 1) << stopped.output;
}

// Every configuration or command-line error is exit status 2 (the systemd unit's
// RestartPreventExitStatus), whatever CLI11 or the check that found it would say.
TEST(HapticdCli, EveryConfigurationOrCommandLineErrorIsExitStatusTwo) {
  const Outcome missing = run_hapticd({"--config", "/nonexistent/hapticd.json"});
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("/nonexistent/hapticd.json"), std::string::npos) << missing.output;
  const Outcome unknown = run_hapticd({"--no-such-option"});
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output;
  const Outcome bad_value = run_hapticd({"--udp-port", "many"});
  EXPECT_EQ(bad_value.exit_code, 2) << bad_value.output;
  const Outcome health_key_alone =
      run_hapticd({"--health-check", "127.0.0.1:1", "--health-key", HAPTICD_BINARY});
  EXPECT_EQ(health_key_alone.exit_code, 2) << health_key_alone.output;
  // Found only when the server is built: a key that is not the certificate's.
  const std::string certs = TEST_CERTS_DIR;
  const std::string path = ::testing::TempDir() + "/wrong_key.json";
  std::ofstream(path) << R"({"time_mode": "LOCKSTEP", "grpc_address": "127.0.0.1:0", "udp_port": 0,
      "security": {"tls": {"cert_file": ")" << certs << R"(/server.pem", "key_file": ")" << certs
                      << R"(/client.key"}}})";
  const Outcome wrong_key = run_hapticd({"--config", path});
  EXPECT_EQ(wrong_key.exit_code, 2) << wrong_key.output;
  EXPECT_NE(wrong_key.output.find("security.tls: the private key does not match the certificate"),
            std::string::npos) << wrong_key.output;
}

TEST(HapticdCli, VersionNamesTheReleaseAndTheApiWireAndDriverVersions) {
  const Outcome version = run_hapticd({"--version"});
  EXPECT_EQ(version.exit_code, 0) << version.output;
  EXPECT_EQ(version.output, std::string("hapticd ") + HAPTIC_VERSION + " (control API " +
                                std::to_string(v1::API_VERSION_CURRENT) + ", wire " +
                                std::to_string(wire::kWireVersion) + ", driver ABI " +
                                std::to_string(HAPTIC_DRIVER_ABI_VERSION) + ")\n");
}

TEST(HapticdCli, WithTlsTooASecondServerOnTheBusyPortFailsWithOneClearLine) {
  const std::string certs = TEST_CERTS_DIR;
  const std::string security = R"("security": {"tls": {"cert_file": ")" + certs +
                               R"(/server.pem", "key_file": ")" + certs + R"(/server.key"}})";
  test::ServerProcess first(R"({"time_mode": "LOCKSTEP", )" + security + "}");
  const std::string grpc = "127.0.0.1:" + std::to_string(first.grpc_port());
  const std::string path = ::testing::TempDir() + "/tls_second.json";
  std::ofstream(path) << R"({"time_mode": "LOCKSTEP", "udp_port": 0, )" + security + "}";
  const Outcome second = run_hapticd({"--config", path, "--grpc-address", grpc});
  EXPECT_EQ(second.exit_code, 1) << second.output;
  EXPECT_NE(second.output.find("cannot listen for gRPC on " + grpc + ": Address already in use"),
            std::string::npos)
      << second.output;
  EXPECT_EQ(std::count(second.output.begin(), second.output.end(), '\n'), 1) << second.output;
  // The first still serves, over TLS: a plaintext check fails, one trusting the CA passes.
  EXPECT_EQ(run_hapticd({"--health-check", grpc}).exit_code, 1);
  const Outcome check = run_hapticd({"--health-check", grpc, "--health-ca", certs + "/ca.pem"});
  EXPECT_EQ(check.exit_code, 0) << check.output;
}

TEST(HapticdCli, PrintConfigNeverShowsATokensSecret) {
  const std::string path = ::testing::TempDir() + "/tokens_config.json";
  std::ofstream(path) << R"({"security": {"tokens": [{"name": "alice", "token": "do-not-print-this-0123",
                                                       "role": "ADMIN"}]}})";
  const Outcome printed = run_hapticd({"--config", path, "--print-config"});
  EXPECT_EQ(printed.exit_code, 0) << printed.output;
  EXPECT_EQ(printed.output.find("do-not-print-this-0123"), std::string::npos) << printed.output;
  EXPECT_NE(printed.output.find("\"alice\""), std::string::npos) << printed.output;
}

TEST(HapticdCli, ADriverBuiltForAnotherAbiIsRefusedAtStartNamingTheLibraryAndBothVersions) {
  const std::string path = ::testing::TempDir() + "/wrong_abi_driver.json";
  std::ofstream(path) << R"({"time_mode": "LOCKSTEP", "grpc_address": "127.0.0.1:0", "udp_port": 0,
                             "driver": {"library": ")" WRONG_ABI_DRIVER R"("}})";
  const Outcome refused = run_hapticd({"--config", path});
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find(WRONG_ABI_DRIVER), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("built for driver ABI version 3, this hapticd speaks versions 1 to 2"),
            std::string::npos)
      << refused.output;
}

// --list-devices asks every driver it finds: the build tree's example lists itself with the params
// that open it; in another folder (--driver-dir), a version 1 driver says it cannot list, and one
// built for another ABI is named with the reason; a library that is no driver is passed over.
TEST(HapticdCli, ListDevicesAsksEveryDriverItFinds) {
  const std::string folder = std::filesystem::path(WRONG_ABI_DRIVER).parent_path().string();
  const Outcome listed = run_hapticd({"--list-devices", "--driver-dir", folder});
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_NE(listed.output.find("point_mass_driver.so (driver ABI 2): 1 device\n"
                               "  \"params\": {}   point mass driver (example plugin, simulated)\n"),
            std::string::npos)
      << listed.output;
  EXPECT_NE(listed.output.find("point_mass_driver_abi1.so (driver ABI 1): cannot list its devices"),
            std::string::npos)
      << listed.output;
  EXPECT_NE(listed.output.find("wrong_abi_driver.so: cannot ask: built for driver ABI version 3"),
            std::string::npos)
      << listed.output;
  const Outcome missing = run_hapticd({"--list-devices", "--driver-dir", "/nonexistent-folder"});
  EXPECT_EQ(missing.exit_code, 2) << missing.output;  // a bad command line
}

TEST(HapticdCli, ADeviceClockedDriverMustRunAtTheLoopRateAndNotInLockstep) {
  const std::string path = ::testing::TempDir() + "/device_clocked_driver.json";
  std::ofstream(path) << R"({"grpc_address": "127.0.0.1:0", "udp_port": 0, "loop_rate_hz": 1000,
                             "real_time": {"use_fifo": false},
                             "driver": {"library": ")" POINT_MASS_DRIVER R"(", "clock": "DEVICE",
                                        "params": {"servo_rate_hz": 2000}}})";
  const Outcome rate = run_hapticd({"--config", path});
  EXPECT_EQ(rate.exit_code, 1) << rate.output;
  EXPECT_NE(rate.output.find("the driver's servo runs at 2000"), std::string::npos) << rate.output;
  const Outcome lockstep = run_hapticd({"--config", path, "--lockstep", "--print-config"});
  EXPECT_EQ(lockstep.exit_code, 2) << lockstep.output;
  EXPECT_NE(lockstep.output.find("driver.clock: DEVICE"), std::string::npos) << lockstep.output;
}

TEST(HapticdCli, ADriverWithoutALibraryOrWithAnUnknownModelIsAConfigurationError) {
  const std::string path = ::testing::TempDir() + "/driver_without_library.json";
  std::ofstream(path) << R"({"driver": {"model": "cartesian"}})";
  const Outcome missing = run_hapticd({"--config", path, "--print-config"});
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("driver.library: the path of the driver's shared library is required"),
            std::string::npos)
      << missing.output;
  std::ofstream(path) << R"({"driver": {"library": "x.so", "model": "five_bar"}})";
  const Outcome model = run_hapticd({"--config", path, "--print-config"});
  EXPECT_EQ(model.exit_code, 2) << model.output;
  EXPECT_NE(model.output.find("driver.model: unknown model \"five_bar\"; expected cartesian"),
            std::string::npos)
      << model.output;
}

}  // namespace
}  // namespace haptic
