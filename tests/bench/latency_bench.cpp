// Loopback latency from a tick to the SDK's state callback, with 1, 8 and 32 clients on one
// real-time server at 1 kHz (in-process, so server time is read directly: latency = server time at
// the callback − the tick's time stamp). Prints p50/p99/p99.9 and each client's received rate, next
// to VRPN's figures measured on a machine like this one (../shared/research/peers.md).
// Usage: latency_bench [seconds-per-case=5] [spin_us=100] [fifo=1]
#include <haptic/haptic.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "app/config.hpp"
#include "app/server.hpp"

namespace {

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

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 5.0;
  haptic::v1::ServerConfig config = haptic::app::default_config();
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  if (argc > 2) config.mutable_real_time()->set_spin_us(static_cast<std::uint32_t>(std::atoi(argv[2])));
  if (argc > 3) config.mutable_real_time()->set_use_fifo(std::atoi(argv[3]) != 0);
  haptic::app::Server server(config);
  server.start();
  const std::string address = "127.0.0.1:" + std::to_string(server.grpc_port());

  std::printf("tick -> SDK callback latency, loopback, 1 kHz real time, %.0f s per case\n", seconds);
  std::printf("%8s  %9s  %8s  %8s  %10s   %s\n", "clients", "rate_Hz", "p50_us", "p99_us", "p99.9_us",
              "VRPN (median / p99, same kind of machine)");
  const char* vrpn[] = {"875 Hz, 24 us / 94 us", "750 Hz, 158-175 us / 356-412 us",
                        "490 Hz, 509-540 us / 1.2-1.4 ms"};
  int row = 0;
  for (const int count : {1, 8, 32}) {
    std::vector<std::unique_ptr<haptic::Client>> clients;
    Recorder recorder;
    recorder.latencies_us.reserve(static_cast<std::size_t>(count * seconds * 1100));
    std::atomic<bool> recording{false};
    for (int i = 0; i < count; ++i) {
      haptic::ClientConfig client_config;
      client_config.server_address = address;
      client_config.client_name = "latency-" + std::to_string(i);
      clients.push_back(std::make_unique<haptic::Client>(client_config));
      clients.back()->on_state([&](const haptic::State& state) {
        const double latency_us =
            (static_cast<double>(server.server_time_ns()) - state.server_time * 1e9) * 1e-3;
        if (!recording.load(std::memory_order_relaxed)) return;
        std::lock_guard lock(recorder.mutex);
        recorder.latencies_us.push_back(latency_us);
      });
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // settle
    recording = true;
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    recording = false;
    for (auto& client : clients) client->on_state({});
    std::vector<double> lat;
    {
      std::lock_guard lock(recorder.mutex);
      lat = recorder.latencies_us;
    }
    const double rate = static_cast<double>(lat.size()) / count / seconds;
    const double p50 = percentile(lat, 0.5), p99 = percentile(lat, 0.99), p999 = percentile(lat, 0.999);
    std::printf("%8d  %9.1f  %8.1f  %8.1f  %10.1f   %s\n", count, rate, p50, p99, p999, vrpn[row++]);
    clients.clear();
  }
  const haptic::v1::Stats stats = server.stats();
  std::printf("server side, tick stamp -> datagram sent (all cases): p50 %.0f us, p99 %.0f us\n",
              stats.send_delay_p50_us(), stats.send_delay_p99_us());
  std::printf("server loop: %.1f Hz, lateness p99 %.0f us, overruns %llu\n", stats.achieved_rate_hz(),
              stats.lateness_p99_us(), static_cast<unsigned long long>(stats.overruns()));
  server.shutdown();
  return 0;
}
