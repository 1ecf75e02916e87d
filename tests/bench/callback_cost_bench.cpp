// What a State costs to reach an application's callback in each language, in one run: a real-time
// hapticd (1 kHz, loopback) streams to one client process at a time, C++ (haptic::Client::on_state,
// this program as `--child`), C (haptic_client_on_state in libhaptic_c, callback_cost_c) and C#
// (Client.OnState under Mono, CallbackCost.exe), alternating for --rounds. Per sample each callback takes the steady clock on its first line and
// subtracts the kernel's receive stamp (State::arrived_at): the receive thread's decoding, the
// binding's conversion and, for C#, the call into managed code. Printed per language: samples,
// p50 and p99 (µs), and p50 as a ratio to C++'s measured in the same run (the issue's targets:
// ≤ 1.2 × for C, ≤ 3 × for C#). Figures only, never an assertion.
//
// Usage: callback_cost_bench [--seconds S=3] [--rounds R=3]
// (a child: callback_cost_bench --child host:port seconds)
#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "integration/run_program.hpp"
#include "integration/server_process.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Delays {
  std::mutex lock;
  std::vector<double> us;  // kernel stamp to the callback's first line
};

/// A child's samples, one number per line (µs).
std::vector<double> run_child(const std::string& binary, const std::vector<std::string>& args) {
  const haptic::test::Outcome outcome = haptic::test::run_program(binary, args);
  std::vector<double> us;
  std::istringstream lines(outcome.output);
  for (std::string line; std::getline(lines, line);) {
    char* end = nullptr;
    const double value = std::strtod(line.c_str(), &end);
    if (end != line.c_str()) us.push_back(value);
  }
  if (outcome.exit_code != 0) std::fprintf(stderr, "%s: %s\n", binary.c_str(), outcome.output.c_str());
  return us;
}

/// The C++ child: prints its samples one per line (µs), as the C and C# children do.
int cpp_child(const std::string& address, double seconds) {
  Delays delays;
  haptic::ClientConfig config;
  config.server_address = address;
  config.client_name = "callback-cost-cpp";
  haptic::Client client(config);
  client.on_state([&delays](const haptic::State& state) {
    const auto now = Clock::now();
    if (!state.arrived_at) return;
    std::lock_guard<std::mutex> guard(delays.lock);
    delays.us.push_back(std::chrono::duration<double, std::micro>(now - *state.arrived_at).count());
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  client.on_state({});
  for (double us : delays.us) std::printf("%.3f\n", us);
  return 0;
}

std::vector<double> run_cpp(const std::string& self, const std::string& address, double seconds) {
  return run_child(self, {"--child", address, std::to_string(seconds)});
}

std::vector<double> run_c(const std::string& address, double seconds) {
  return run_child(CALLBACK_COST_C, {address, std::to_string(seconds)});
}

std::vector<double> run_csharp(const std::string& address, double seconds) {
  return run_child(MONO_BINARY, {CALLBACK_COST_EXE, address, std::to_string(seconds)});
}

}  // namespace

namespace {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<std::size_t>(p * static_cast<double>(values.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--child") == 0) return cpp_child(argv[2], std::atof(argv[3]));
  double seconds = 3.0;
  int rounds = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--seconds") == 0) seconds = std::atof(argv[i + 1]);
    else if (std::strcmp(argv[i], "--rounds") == 0) rounds = std::atoi(argv[i + 1]);
  }
  haptic::test::ServerProcess server(R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1",
      "status_period_s": 0, "real_time": {"use_fifo": false}})");
  std::vector<double> cpp, c, cs;
  for (int round = 0; round < rounds; ++round) {
    std::fprintf(stderr, "round %d/%d: C++, C, C# for %.1f s each\n", round + 1, rounds, seconds);
    for (double v : run_cpp(argv[0], server.address(), seconds)) cpp.push_back(v);
    for (double v : run_c(server.address(), seconds)) c.push_back(v);
    for (double v : run_csharp(server.address(), seconds)) cs.push_back(v);
  }
  const double base = percentile(cpp, 0.5);
  std::printf("kernel receive stamp to the callback's first line, 1 kHz stream on loopback, %d rounds of %.1f s\n",
              rounds, seconds);
  std::printf("%-4s  %8s  %8s  %8s  %s\n", "lang", "samples", "p50_us", "p99_us", "p50 / C++");
  const auto row = [&](const char* name, const std::vector<double>& v) {
    std::printf("%-4s  %8zu  %8.2f  %8.2f  %.2f\n", name, v.size(), percentile(v, 0.5), percentile(v, 0.99),
                base > 0 ? percentile(v, 0.5) / base : 0.0);
  };
  row("C++", cpp);
  row("C", c);
  row("C#", cs);
  return cpp.empty() || c.empty() || cs.empty() ? 1 : 0;
}
