// What a State costs to reach an application's callback in each language, in one run: a real-time
// hapticd (1 kHz, loopback, its HTTP face on for C#) streams to one client process at a time, C++
// (haptic::Client::on_state, this program as `--child`), C (haptic_client_on_state in
// libhaptic_c, callback_cost_c) and C# (the managed client's Client.OnState under Mono,
// CallbackCost.exe), alternating for --rounds. Two figures per language:
// - CPU per sample: the client process's CPU time (user + system, after 0.5 s of warm-up) over
//   the samples its callback got: everything the client spends to receive, check, decode and hand
//   over a sample, heartbeats included. As a ratio to C++'s (the managed client's target: ≤ 2 ×).
// - Delay: per sample, the callback's first line's steady clock minus the kernel's receive stamp
//   (State::arrived_at) for C++ and C; the managed client has no kernel stamp (.NET reads none),
//   so its delay is from its own read of the socket (State.ReceivedAtNs): a shorter path, shown
//   apart. p50 and p99 (µs).
// Figures only, never an assertion.
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

#include <sys/resource.h>

#include "integration/run_program.hpp"
#include "integration/server_process.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Delays {
  std::mutex lock;
  std::vector<double> us;  // kernel stamp to the callback's first line
  std::uint64_t calls = 0;
};

/// What one child printed: its first line "cpu_us_per_sample V samples N", then its delays, one
/// number per line (µs).
struct ChildResult {
  std::vector<double> us;
  std::vector<double> cpu_us_per_sample;  // one per run
  std::uint64_t samples = 0;
};

void run_child(const std::string& binary, const std::vector<std::string>& args, ChildResult& into) {
  const haptic::test::Outcome outcome = haptic::test::run_program(binary, args);
  std::istringstream lines(outcome.output);
  for (std::string line; std::getline(lines, line);) {
    double cpu = 0.0;
    unsigned long long samples = 0;
    if (std::sscanf(line.c_str(), "cpu_us_per_sample %lf samples %llu", &cpu, &samples) == 2) {
      into.cpu_us_per_sample.push_back(cpu);
      into.samples += samples;
      continue;
    }
    char* end = nullptr;
    const double value = std::strtod(line.c_str(), &end);
    if (end != line.c_str()) into.us.push_back(value);
  }
  if (outcome.exit_code != 0) std::fprintf(stderr, "%s: %s\n", binary.c_str(), outcome.output.c_str());
}

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
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
    std::lock_guard<std::mutex> guard(delays.lock);
    ++delays.calls;
    if (!state.arrived_at) return;
    delays.us.push_back(std::chrono::duration<double, std::micro>(now - *state.arrived_at).count());
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // warm-up
  const auto calls_before = [&] { std::lock_guard<std::mutex> guard(delays.lock); return delays.calls; }();
  const double cpu_before = cpu_seconds();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const double cpu = cpu_seconds() - cpu_before;
  const auto calls = [&] { std::lock_guard<std::mutex> guard(delays.lock); return delays.calls; }() - calls_before;
  client.on_state({});
  std::printf("cpu_us_per_sample %.3f samples %llu\n", calls > 0 ? cpu * 1e6 / static_cast<double>(calls) : 0.0,
              static_cast<unsigned long long>(calls));
  for (double us : delays.us) std::printf("%.3f\n", us);
  return 0;
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
      "http_address": "127.0.0.1:0", "status_period_s": 0, "real_time": {"use_fifo": false}})");
  const std::string http = "127.0.0.1:" + std::to_string(server.http_port());
  const std::string duration = std::to_string(seconds);
  ChildResult cpp, c, cs;
  for (int round = 0; round < rounds; ++round) {
    std::fprintf(stderr, "round %d/%d: C++, C, C# for %.1f s each\n", round + 1, rounds, seconds);
    run_child(argv[0], {"--child", server.address(), duration}, cpp);
    run_child(CALLBACK_COST_C, {server.address(), duration}, c);
    run_child(MONO_BINARY, {CALLBACK_COST_EXE, http, duration}, cs);
  }
  const auto median = [](std::vector<double> v) { return percentile(std::move(v), 0.5); };
  const double base_cpu = median(cpp.cpu_us_per_sample);
  const double base_delay = percentile(cpp.us, 0.5);
  std::printf("1 kHz stream on loopback, %d rounds of %.1f s per language\n", rounds, seconds);
  std::printf("%-4s  %8s  %12s  %9s  %8s  %8s  %9s  %s\n", "lang", "samples", "cpu_us/sample", "cpu / C++",
              "p50_us", "p99_us", "p50 / C++", "delay from");
  const auto row = [&](const char* name, const ChildResult& r, const char* from, bool comparable) {
    std::printf("%-4s  %8llu  %12.2f  %9.2f  %8.2f  %8.2f  %9s  %s\n", name, static_cast<unsigned long long>(r.samples),
                median(r.cpu_us_per_sample), base_cpu > 0 ? median(r.cpu_us_per_sample) / base_cpu : 0.0,
                percentile(r.us, 0.5), percentile(r.us, 0.99),
                comparable && base_delay > 0 ? std::to_string(percentile(r.us, 0.5) / base_delay).substr(0, 4).c_str() : "-",
                from);
  };
  row("C++", cpp, "kernel stamp", true);
  row("C", c, "kernel stamp", true);
  row("C#", cs, "its socket read", false);
  return cpp.cpu_us_per_sample.empty() || c.cpu_us_per_sample.empty() || cs.cpu_us_per_sample.empty() ? 1 : 0;
}
