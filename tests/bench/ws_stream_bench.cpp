// What WebSocket state streams cost the real-time loop, in one run: an in-process hapticd at
// 1 kHz in real time with the HTTP face; first the loop alone for one statistics window, then
// with N sessions each taking the state stream over a WebSocket at R Hz (docs/http.md) for
// another. Prints the loop's lateness (p50 / p99 / p99.9 / max over the window) and overruns in
// each phase and their ratios, the messages each stream received against what its rate asks, and
// the samples' age on arrival (server time now − the tick's stamp; the client shares the host's
// clock). A benchmark: it prints figures, asserts nothing.
//
// Usage: ws_stream_bench [--streams N=8] [--rate HZ=250]

#include <time.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/server.hpp"
#include "config/server_config.hpp"
#include "haptic/wire/datagram.hpp"
#include "net/http_face.hpp"
#include "net/proto_json.hpp"
#include "support/http_client.hpp"

namespace {

namespace beast = boost::beast;
using tcp = boost::asio::ip::tcp;

std::int64_t monotonic_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

/// One HTTP call on a fresh connection: the reply's body ("" on failure).
std::string post(std::uint16_t port, const std::string& call, const std::string& body) {
  haptic::test::HttpConnection connection(port);
  connection.send("POST /haptic.v1.Haptic/" + call + " HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                  "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
                  "\r\n\r\n" + body);
  return connection.read_reply().body;
}

struct StreamFigures {
  std::uint64_t messages = 0;
  std::vector<double> ages_us;
};

/// Voluntary context switches (wake-ups after a wait) of this process's threads whose name starts
/// with one of `prefixes`, summed.
std::uint64_t wakeups_of(const std::vector<std::string>& prefixes) {
  std::uint64_t total = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    if (std::none_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) { return name.rfind(p, 0) == 0; })) {
      continue;
    }
    std::ifstream status(task.path() / "status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("voluntary_ctxt_switches:", 0) == 0) total += std::strtoull(line.c_str() + 24, nullptr, 10);
    }
  }
  return total;
}

struct Phase {
  haptic::v1::Stats stats;
  std::uint64_t overruns = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int streams = 8;
  double rate = 250.0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--streams" && i + 1 < argc) streams = std::atoi(argv[++i]);
    else if (arg == "--rate" && i + 1 < argc) rate = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: ws_stream_bench [--streams N] [--rate HZ]\n");
      return 2;
    }
  }
  if (streams < 1 || streams > 60 || !(rate >= 1.0 && rate <= 1000.0)) {
    std::fprintf(stderr, "ws_stream_bench: --streams must be 1 to 60 and --rate 1 to 1000\n");
    return 2;
  }
  haptic::v1::ServerConfig config = haptic::config::default_config();
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  config.set_http_address("127.0.0.1:0");
  config.set_max_sessions(64);
  config.set_max_sessions_per_peer(64);
  config.set_session_open_burst_per_peer(64);
  haptic::app::Server server(config);
  server.start();
  const std::uint16_t port = server.http_port();
  const double window_s = server.stats().window_s();
  const auto settle = [&] {  // the start's own lateness out of the window first
    std::this_thread::sleep_for(std::chrono::duration<double>(window_s));
  };
  settle();
  const auto phase = [&] {
    const std::uint64_t before = server.stats().overruns();
    std::this_thread::sleep_for(std::chrono::duration<double>(window_s));
    Phase p;
    p.stats = server.stats();
    p.overruns = p.stats.overruns() - before;
    return p;
  };
  std::printf("hapticd at %.0f Hz in real time; each phase one statistics window (%.0f s)\n",
              config.loop_rate_hz(), window_s);
  const Phase alone = phase();

  std::atomic<bool> stop{false};
  // Messages are counted from here (once every stream runs) until stop.
  std::atomic<std::int64_t> count_from_ns{INT64_MAX};
  std::vector<StreamFigures> figures(static_cast<std::size_t>(streams));
  std::vector<std::thread> readers;
  const std::int64_t origin_ns = server.time_origin_ns().value_or(0);
  for (int s = 0; s < streams; ++s) {
    haptic::v1::OpenSessionRequest open;
    open.set_client_name("ws-bench-" + std::to_string(s));
    open.set_api_version(haptic::v1::API_VERSION_CURRENT);
    haptic::v1::OpenSessionResponse session;
    if (!haptic::net::from_json(post(port, "OpenSession", haptic::net::to_json(open)), session).empty()) {
      std::fprintf(stderr, "ws_stream_bench: OpenSession failed\n");
      return 1;
    }
    readers.emplace_back([&, s, session] {
      boost::asio::io_context io;
      tcp::socket socket(io);
      socket.connect(tcp::endpoint(boost::asio::ip::make_address("127.0.0.1"), port));
      beast::websocket::stream<tcp::socket> ws(std::move(socket));
      ws.handshake("127.0.0.1", "/haptic.v1.Haptic/StreamState");
      const std::string secret = haptic::net::encode_base64(session.session_secret());
      char rate_text[32];
      std::snprintf(rate_text, sizeof rate_text, "%g", rate);
      ws.write(boost::asio::buffer(R"({"request": {"session_id": ")" + std::to_string(session.session_id()) +
                                   R"(", "rate_hz": )" + rate_text + R"(}, "session_secret": ")" + secret + "\"}"));
      haptic::wire::Key key{};
      std::copy(session.udp_key().begin(), session.udp_key().end(), key.begin());
      StreamFigures& mine = figures[static_cast<std::size_t>(s)];
      while (!stop.load()) {
        beast::flat_buffer buffer;
        beast::error_code error;
        ws.read(buffer, error);
        if (error) break;
        const auto arrived_ns = monotonic_ns();
        const std::string message = beast::buffers_to_string(buffer.data());
        haptic::wire::Header header;
        haptic::wire::StatePayload state;
        if (haptic::wire::decode_state({reinterpret_cast<const std::uint8_t*>(message.data()), message.size()},
                                       key, header, state) != haptic::wire::DecodeError::kNone) {
          continue;
        }
        if (arrived_ns < count_from_ns.load() || stop.load()) continue;
        ++mine.messages;
        mine.ages_us.push_back(static_cast<double>(arrived_ns - origin_ns - header.time_ns) * 1e-3);
      }
      beast::error_code ignored;
      ws.close(beast::websocket::close_code::normal, ignored);
    });
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));  // every stream running first
  count_from_ns.store(monotonic_ns());
  // The server's stream threads: the WebSockets' handlers and the pacer that sends for them.
  const std::vector<std::string> stream_threads{"ws-http", "state-pacer"};
  const std::uint64_t wakeups_before = wakeups_of(stream_threads);
  const Phase streaming = phase();
  const std::uint64_t wakeups = wakeups_of(stream_threads) - wakeups_before;
  stop.store(true);
  server.shutdown();
  for (std::thread& reader : readers) reader.join();

  std::printf("%-28s %9s %9s %9s %9s %9s\n", "phase", "p50_us", "p99_us", "p99.9_us", "max_us", "overruns");
  const auto row = [](const char* name, const Phase& p) {
    std::printf("%-28s %9.1f %9.1f %9.1f %9.1f %9llu\n", name, p.stats.lateness_p50_us(), p.stats.lateness_p99_us(),
                p.stats.lateness_p999_us(), p.stats.lateness_max_us(), static_cast<unsigned long long>(p.overruns));
  };
  row("loop alone", alone);
  char name[64];
  std::snprintf(name, sizeof name, "%d WebSocket streams @ %.0f Hz", streams, rate);
  row(name, streaming);
  std::printf("lateness ratio (+1 us) with/without: p50 %.2f, p99 %.2f, p99.9 %.2f\n",
              (streaming.stats.lateness_p50_us() + 1) / (alone.stats.lateness_p50_us() + 1),
              (streaming.stats.lateness_p99_us() + 1) / (alone.stats.lateness_p99_us() + 1),
              (streaming.stats.lateness_p999_us() + 1) / (alone.stats.lateness_p999_us() + 1));
  std::printf("the server's stream threads woke %.0f times a second (%d streams at %.0f Hz)\n",
              static_cast<double>(wakeups) / window_s, streams, rate);
  std::vector<double> ages;
  std::uint64_t least = ~0ull, most = 0;
  for (const StreamFigures& f : figures) {
    least = std::min(least, f.messages);
    most = std::max(most, f.messages);
    ages.insert(ages.end(), f.ages_us.begin(), f.ages_us.end());
  }
  std::sort(ages.begin(), ages.end());
  const double expected = rate * window_s;
  std::printf("messages per stream over the window: %llu to %llu (the rate asks %.0f: %.1f%% to %.1f%%)\n",
              static_cast<unsigned long long>(least), static_cast<unsigned long long>(most), expected,
              100.0 * static_cast<double>(least) / expected, 100.0 * static_cast<double>(most) / expected);
  if (!ages.empty()) {
    std::printf("sample age on arrival: p50 %.0f us, p99 %.0f us, max %.0f us (%zu samples)\n",
                ages[ages.size() / 2], ages[static_cast<std::size_t>(0.99 * static_cast<double>(ages.size() - 1))],
                ages.back(), ages.size());
  }
  return 0;
}
