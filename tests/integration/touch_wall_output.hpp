#pragma once
// What the tests that compare touch_wall's ports (C, C#) with the C++ program compare.

#include <gtest/gtest.h>

#include <functional>
#include <regex>
#include <string>
#include <vector>

#include "integration/run_program.hpp"
#include "integration/server_process.hpp"

namespace haptic::test {

/// touch_wall's output with the count of datagrams received blanked: how many State datagrams
/// arrived by the end depends on the network's timing even in lockstep (the program says so).
inline std::string without_datagram_count(const std::string& output) {
  return std::regex_replace(output, std::regex("[0-9]+ datagrams received"), "N datagrams received");
}

/// Runs one touch_wall with these arguments to its end.
using TouchWallRun = std::function<Outcome(const std::vector<std::string>& args)>;

/// What the port's client speaks to: the gRPC address (C, over the C++ SDK) or the HTTP face (C#).
enum class PortSpeaks { kGrpc, kHttp };

/// `port` prints what the C++ `cpp` prints, each against a fresh lockstep server: the simulated
/// hand pressing, and the device's own hand watched (the datagram count apart); and it refuses the
/// same bad options with the same words and status.
inline void expect_prints_what_cpp_prints(const TouchWallRun& cpp, const TouchWallRun& port,
                                          PortSpeaks speaks = PortSpeaks::kGrpc) {
  for (const std::vector<std::string>& options :
       {std::vector<std::string>{"--lockstep"}, std::vector<std::string>{"--lockstep", "--hand", "--seconds", "1"}}) {
    ServerProcess for_cpp(lockstep_config());
    std::vector<std::string> args = {for_cpp.address()};
    args.insert(args.end(), options.begin(), options.end());
    const Outcome expected = cpp(args);
    ASSERT_EQ(expected.exit_code, 0) << expected.output;
    ASSERT_GT(expected.output.size(), 1000u) << expected.output;

    ServerProcess for_port(lockstep_config(speaks == PortSpeaks::kHttp ? R"("http_address": "127.0.0.1:0")" : ""));
    args[0] = speaks == PortSpeaks::kHttp ? "127.0.0.1:" + std::to_string(for_port.http_port()) : for_port.address();
    const Outcome got = port(args);
    ASSERT_EQ(got.exit_code, 0) << got.output;
    EXPECT_EQ(without_datagram_count(got.output), without_datagram_count(expected.output));
  }
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--cert", "client.pem"}, std::vector<std::string>{"--tls"},
        std::vector<std::string>{"--seconds", "forever"},
        std::vector<std::string>{"0.0.0.0:1", "--token", "lab-controller-token-0123456789"}}) {
    const Outcome expected = cpp(bad);
    const Outcome got = port(bad);
    EXPECT_EQ(got.exit_code, expected.exit_code) << got.output;
    EXPECT_EQ(got.output, expected.output);
  }
}

}  // namespace haptic::test
