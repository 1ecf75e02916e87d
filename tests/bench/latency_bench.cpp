// Loopback latency from a tick to the SDK's state callback — the age of each sample when the
// application gets it — with 1, 8, 32 and 64 clients on one real-time server at 1 kHz. Prints
// p50/p99/p99.9, each client's received rate and how many samples were skipped for a newer one,
// next to VRPN's figures measured on a machine like this one (../shared/research/peers.md).
//
// Two ways to hold the clients:
//   threads   (default) every client in this process beside the server: latency = server time at
//             the callback − the tick's time stamp, read directly;
//   processes every client in a process of its own (this program, re-run with --client), as VRPN's
//             clients were measured: latency = CLOCK_MONOTONIC at the callback − the tick's stamp
//             mapped to CLOCK_MONOTONIC through the server's start time, which is passed to each
//             client (one clock for every process on a machine).
// Usage: latency_bench [seconds-per-case=5] [spin_us=100] [fifo=1] [threads|processes]
#include <haptic/haptic.hpp>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "config/server_config.hpp"
#include "app/server.hpp"

extern char** environ;

namespace {

constexpr auto kSettle = std::chrono::milliseconds(200);  // before recording starts

struct Recorder {
  std::mutex mutex;
  std::vector<double> latencies_us;
};

double percentile(std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

std::int64_t monotonic_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// Connects one client, records `seconds` of latencies after the settling time, and returns them.
/// `server_time_now_ns` gives the server's time now (in-process: read from the server; another
/// process: CLOCK_MONOTONIC less the server's start).
std::vector<double> record_client(const std::string& address, const std::string& name, double seconds,
                                  const std::function<std::int64_t()>& server_time_now_ns) {
  Recorder recorder;
  recorder.latencies_us.reserve(static_cast<std::size_t>(seconds * 1100));
  std::atomic<bool> recording{false};
  haptic::ClientConfig config;
  config.server_address = address;
  config.client_name = name;
  haptic::Client client(config);
  client.on_state([&](const haptic::State& state) {
    const double latency_us = (static_cast<double>(server_time_now_ns()) - state.server_time * 1e9) * 1e-3;
    if (!recording.load(std::memory_order_relaxed)) return;
    std::lock_guard lock(recorder.mutex);
    recorder.latencies_us.push_back(latency_us);
  });
  std::this_thread::sleep_for(kSettle);
  recording = true;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  recording = false;
  client.on_state({});
  std::lock_guard lock(recorder.mutex);
  return recorder.latencies_us;
}

/// Child mode: latency_bench --client ADDRESS SERVER_START_NS SECONDS OUT_FILE NAME.
int run_child(char** argv) {
  const std::string address = argv[2];
  const std::int64_t server_start_ns = std::atoll(argv[3]);
  const double seconds = std::atof(argv[4]);
  const std::vector<double> latencies =
      record_client(address, argv[6], seconds, [server_start_ns] { return monotonic_ns() - server_start_ns; });
  std::ofstream out(argv[5], std::ios::binary);
  out.write(reinterpret_cast<const char*>(latencies.data()),
            static_cast<std::streamsize>(latencies.size() * sizeof(double)));
  return out ? 0 : 1;
}

/// `count` clients, each in a process of its own; their latencies, merged.
std::vector<double> record_in_processes(const std::string& address, std::int64_t server_start_ns, int count,
                                        double seconds) {
  std::vector<pid_t> children;
  std::vector<std::string> files;
  const std::string self = "/proc/self/exe";
  for (int i = 0; i < count; ++i) {
    files.push_back("/tmp/latency_bench." + std::to_string(getpid()) + "." + std::to_string(i));
    std::vector<std::string> args = {"latency_bench", "--client", address, std::to_string(server_start_ns),
                                     std::to_string(seconds), files.back(), "latency-" + std::to_string(i)};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawn(&pid, self.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
      std::perror("latency_bench: posix_spawn");
      std::exit(1);
    }
    children.push_back(pid);
  }
  std::vector<double> merged;
  for (int i = 0; i < count; ++i) {
    int status = 0;
    waitpid(children[static_cast<std::size_t>(i)], &status, 0);
    std::ifstream in(files[static_cast<std::size_t>(i)], std::ios::binary);
    double value = 0.0;
    while (in.read(reinterpret_cast<char*>(&value), sizeof value)) merged.push_back(value);
    std::remove(files[static_cast<std::size_t>(i)].c_str());
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "latency_bench: client process %d failed\n", i);
    }
  }
  return merged;
}

/// `count` clients on threads of this process; their latencies, merged.
std::vector<double> record_in_threads(const std::string& address, haptic::app::Server& server, int count,
                                      double seconds) {
  std::vector<std::vector<double>> per_client(static_cast<std::size_t>(count));
  std::vector<std::thread> threads;
  for (int i = 0; i < count; ++i) {
    threads.emplace_back([&, i] {
      per_client[static_cast<std::size_t>(i)] = record_client(
          address, "latency-" + std::to_string(i), seconds, [&server] { return server.server_time_ns(); });
    });
  }
  for (std::thread& t : threads) t.join();
  std::vector<double> merged;
  for (const auto& v : per_client) merged.insert(merged.end(), v.begin(), v.end());
  return merged;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 7 && std::strcmp(argv[1], "--client") == 0) return run_child(argv);
  const double seconds = argc > 1 ? std::atof(argv[1]) : 5.0;
  haptic::v1::ServerConfig config = haptic::config::default_config();
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  config.set_max_sessions(64);  // every client on this one host
  config.set_max_sessions_per_peer(64);
  if (argc > 2) config.mutable_real_time()->set_spin_us(static_cast<std::uint32_t>(std::atoi(argv[2])));
  if (argc > 3) config.mutable_real_time()->set_use_fifo(std::atoi(argv[3]) != 0);
  const bool processes = argc > 4 && std::strcmp(argv[4], "processes") == 0;
  if (argc > 4 && !processes && std::strcmp(argv[4], "threads") != 0) {
    std::fprintf(stderr, "latency_bench: the 4th argument must be threads or processes, got \"%s\"\n", argv[4]);
    return 2;
  }
  haptic::app::Server server(config);
  server.start();
  const std::string address = "127.0.0.1:" + std::to_string(server.grpc_port());
  const std::int64_t server_start_ns = monotonic_ns() - server.server_time_ns();

  std::printf("tick -> SDK callback latency, loopback, 1 kHz real time, %.0f s per case, clients in %s\n",
              seconds, processes ? "their own processes" : "threads of the server's process");
  std::printf("%8s  %9s  %8s  %8s  %10s   %s\n", "clients", "rate_Hz", "p50_us", "p99_us", "p99.9_us",
              "VRPN (median / p99, same kind of machine)");
  const char* vrpn[] = {"875 Hz, 24 us / 94 us", "750 Hz, 158-175 us / 356-412 us",
                        "490 Hz, 509-540 us / 1.2-1.4 ms", "132-265 Hz, 654 us / 4.4 ms (side by side)"};
  int row = 0;
  for (const int count : {1, 8, 32, 64}) {
    std::vector<double> lat = processes ? record_in_processes(address, server_start_ns, count, seconds)
                                        : record_in_threads(address, server, count, seconds);
    const double rate = static_cast<double>(lat.size()) / count / seconds;
    const double p50 = percentile(lat, 0.5), p99 = percentile(lat, 0.99), p999 = percentile(lat, 0.999);
    std::printf("%8d  %9.1f  %8.1f  %8.1f  %10.1f   %s\n", count, rate, p50, p99, p999, vrpn[row++]);
  }
  const haptic::v1::Stats stats = server.stats();
  std::printf("server side, tick stamp -> datagram sent (all cases): p50 %.0f us, p99 %.0f us\n",
              stats.send_delay_p50_us(), stats.send_delay_p99_us());
  std::printf("server loop: %.1f Hz, lateness p99 %.0f us, overruns %llu\n", stats.achieved_rate_hz(),
              stats.lateness_p99_us(), static_cast<unsigned long long>(stats.overruns()));
  server.shutdown();
  return 0;
}
