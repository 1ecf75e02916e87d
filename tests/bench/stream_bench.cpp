// The pose/force stream against its floor, in one run: hapticd's State stream to N client
// processes beside a bare UDP sender with the same payload, the same fan-out and the same kind of
// receivers, one system at a time, alternating, so that every figure is also a ratio to the floor
// measured minutes apart on the same host.
//
//   floor    one SCHED_FIFO thread (hapticd's loop priority and CPU) wakes at each 1 ms deadline as
//            the loop does (sleep, then spin the last spin_us) and sendto()s a 164-byte datagram
//            (a State's size) to every receiver in turn; each receiver blocks in recvmsg().
//   hapticd  the server with its default configuration (real time, 1 kHz) on loopback; each client
//            process uses the SDK and records in its State callback, as an application would.
//
// The receiving processes' own CPU per sample is printed too ("client us"): on one host the
// clients share the cores with the server, so their cost is part of every age.
// Per sample every client records the tick's deadline (the floor's stamp; hapticd's State
// server_time mapped to CLOCK_MONOTONIC through the server's start), the kernel's receive time
// (SO_TIMESTAMPNS; the SDK reports it as State::arrived_at) and the moment the application has it.
// So the age splits into server + network (deadline -> kernel) and client scheduling (kernel ->
// application). Per case: each client's rate (slowest / median), age p50 / p99 / p99.9, the
// sending process's CPU (getrusage; the clients are other processes) and the loop's overruns.
//
// Usage: stream_bench [--seconds S=10] [--clients 1,8,32,64] [--rounds R=1] [--csv FILE]
//                     [--sender-cpu N] [--sender-priority P]  (hapticd's real_time.sender_cpu, _priority)
// (a child: stream_bench --client floor|hapticd TARGET ORIGIN_NS SECONDS OUT_FILE INDEX)
#include <haptic/haptic.hpp>
#include <netinet/in.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app/server.hpp"
#include "config/server_config.hpp"
#include "haptic/wire/datagram.hpp"
#include "runtime/loop_cpu.hpp"
#include "runtime/realtime.hpp"

extern char** environ;

namespace {

constexpr auto kSettle = std::chrono::milliseconds(300);  // after every client is connected
constexpr std::size_t kPayloadSize = haptic::wire::kStateDatagramSize;  // 164 bytes

/// One sample as a client saw it. Times are CLOCK_MONOTONIC, ns; 0 where not known.
struct Sample {
  std::int64_t deadline_ns = 0;  // the tick's stamp
  std::int64_t kernel_ns = 0;    // the kernel's receive time
  std::int64_t app_ns = 0;       // the application has it
};

std::int64_t clock_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
std::int64_t monotonic_ns() { return clock_ns(CLOCK_MONOTONIC); }

/// CLOCK_REALTIME − CLOCK_MONOTONIC now (SO_TIMESTAMPNS stamps are CLOCK_REALTIME).
std::int64_t realtime_offset_ns() {
  const std::int64_t a = monotonic_ns();
  const std::int64_t r = clock_ns(CLOCK_REALTIME);
  const std::int64_t b = monotonic_ns();
  return r - (a + b) / 2;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

/// This process's CPU time so far (user + system). Unit: ns.
std::int64_t process_cpu_ns() { return clock_ns(CLOCK_PROCESS_CPUTIME_ID); }

/// The samples, then one record {-1, CPU ns over the recording, 0}: the client's own cost.
void write_samples(const std::string& path, const std::vector<Sample>& samples, std::int64_t cpu_ns) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(samples.data()),
            static_cast<std::streamsize>(samples.size() * sizeof(Sample)));
  const Sample cost{-1, cpu_ns, 0};
  out.write(reinterpret_cast<const char*>(&cost), sizeof cost);
}

// ---------------------------------------------------------------------------------------------
// Clients.

/// A floor receiver: registers with the sender (a datagram to its port, repeated until data
/// comes), then blocks in recvmsg() and records every datagram.
int run_floor_client(std::uint16_t port, double seconds, const std::string& out_path) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  const int on = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  timeval timeout{0, 100'000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const std::int64_t offset = realtime_offset_ns();
  std::vector<Sample> samples;
  samples.reserve(static_cast<std::size_t>(seconds * 1100) + 64);
  std::int64_t record_from = 0, record_until = 0, cpu_from = -1;
  std::uint8_t buffer[2048];
  alignas(cmsghdr) char control[256];
  for (;;) {
    if (record_from == 0) ::sendto(fd, "hello", 5, 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
    iovec iov{buffer, sizeof buffer};
    msghdr message{};
    message.msg_iov = &iov;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    const ssize_t size = ::recvmsg(fd, &message, 0);
    const std::int64_t now = monotonic_ns();
    if (record_from == 0 && size > 0) {
      record_from = now + std::chrono::nanoseconds(kSettle).count();
      record_until = record_from + static_cast<std::int64_t>(seconds * 1e9);
    }
    if (record_from != 0 && now >= record_until) break;
    if (size < static_cast<ssize_t>(2 * sizeof(std::int64_t)) || now < record_from) continue;
    if (cpu_from < 0) cpu_from = process_cpu_ns();
    Sample sample;
    std::memcpy(&sample.deadline_ns, buffer, sizeof(std::int64_t));
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        sample.kernel_ns = static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec - offset;
      }
    }
    sample.app_ns = now;
    samples.push_back(sample);
  }
  const std::int64_t cpu = process_cpu_ns() - cpu_from;
  ::close(fd);
  write_samples(out_path, samples, cpu);
  return 0;
}

/// An SDK client: subscribes at the full rate and records in its State callback.
int run_hapticd_client(const std::string& address, std::int64_t origin_ns, double seconds,
                       const std::string& out_path, int index) {
  std::mutex mutex;
  std::vector<Sample> samples;
  samples.reserve(static_cast<std::size_t>(seconds * 1100) + 64);
  std::atomic<bool> recording{false};
  haptic::ClientConfig config;
  config.server_address = address;
  config.client_name = "stream-bench-" + std::to_string(index);
  haptic::Client client(config);
  client.on_state([&](const haptic::State& state) {
    const std::int64_t now = monotonic_ns();
    if (!recording.load(std::memory_order_relaxed)) return;
    Sample sample;
    sample.deadline_ns = origin_ns + static_cast<std::int64_t>(std::llround(state.server_time * 1e9));
    if (state.arrived_at) {
      sample.kernel_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             state.arrived_at->time_since_epoch())
                             .count();
    }
    sample.app_ns = now;
    std::lock_guard lock(mutex);
    samples.push_back(sample);
  });
  std::this_thread::sleep_for(kSettle);
  const std::int64_t cpu_from = process_cpu_ns();
  recording = true;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  recording = false;
  const std::int64_t cpu = process_cpu_ns() - cpu_from;
  client.on_state({});
  std::lock_guard lock(mutex);
  write_samples(out_path, samples, cpu);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// The senders.

/// The floor: one real-time thread, one sendto() per receiver per tick.
class FloorSender {
 public:
  FloorSender(int priority, int cpu, std::int64_t spin_ns) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address);
    socklen_t length = sizeof address;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length);
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this, priority, cpu, spin_ns] { run(priority, cpu, spin_ns); });
  }
  ~FloorSender() {
    stop_ = true;
    thread_.join();
    ::close(fd_);
  }
  std::uint16_t port() const { return port_; }
  std::uint64_t overruns() const { return overruns_; }

 private:
  void run(int priority, int cpu, std::int64_t spin_ns) {
    (void)haptic::runtime::apply_realtime(priority);
    if (cpu >= 0) (void)haptic::runtime::pin_to_cpu(cpu);
    std::vector<sockaddr_in> receivers;
    std::uint8_t payload[kPayloadSize] = {};
    constexpr std::int64_t kPeriod = 1'000'000;
    std::int64_t deadline = monotonic_ns() + kPeriod;
    while (!stop_) {
      haptic::runtime::sleep_then_spin_until(deadline, spin_ns);
      for (;;) {  // new receivers: their hello datagrams
        sockaddr_in from{};
        socklen_t length = sizeof from;
        char hello[16];
        if (::recvfrom(fd_, hello, sizeof hello, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &length) < 0) break;
        if (std::none_of(receivers.begin(), receivers.end(), [&](const sockaddr_in& r) {
              return r.sin_port == from.sin_port && r.sin_addr.s_addr == from.sin_addr.s_addr;
            })) {
          receivers.push_back(from);
        }
      }
      std::memcpy(payload, &deadline, sizeof deadline);
      for (const sockaddr_in& to : receivers) {
        ::sendto(fd_, payload, sizeof payload, MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&to), sizeof to);
      }
      deadline += kPeriod;
      if (const std::int64_t now = monotonic_ns(); now > deadline) {
        const std::int64_t missed = (now - deadline) / kPeriod + 1;
        overruns_ += static_cast<std::uint64_t>(missed);
        deadline += missed * kPeriod;
      }
    }
  }

  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> overruns_{0};
  std::thread thread_;
};

// ---------------------------------------------------------------------------------------------
// One case.

struct Case {
  std::string system;
  int clients = 0;
  double rate_slowest = 0.0, rate_median = 0.0;
  double p50 = 0.0, p99 = 0.0, p999 = 0.0;   // deadline -> application, µs
  double net_p50 = 0.0, net_p99 = 0.0;       // deadline -> kernel, µs (0: not known)
  double app_p50 = 0.0, app_p99 = 0.0;       // kernel -> application, µs
  double cpu_percent = 0.0;                  // the sending process, % of one core
  double client_cpu_us = 0.0;                // the receiving processes' CPU per sample, µs
  std::uint64_t overruns = 0;
  double first_send_p50 = 0.0, first_send_p99 = 0.0;  // hapticd: tick stamp -> datagrams handed over, µs
};

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// Spawns `count` clients of `system`, waits for them, and reads what they recorded.
std::vector<std::vector<Sample>> run_clients(const std::string& system, const std::string& target,
                                             std::int64_t origin_ns, int count, double seconds,
                                             double& cpu_percent, double& client_cpu_us_per_sample) {
  std::vector<pid_t> children;
  std::vector<std::string> files;
  for (int i = 0; i < count; ++i) {
    files.push_back("/tmp/stream_bench." + std::to_string(getpid()) + "." + std::to_string(i));
    std::vector<std::string> args = {"stream_bench", "--client", system, target, std::to_string(origin_ns),
                                     std::to_string(seconds), files.back(), std::to_string(i)};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, argv.data(), environ) != 0) {
      std::perror("stream_bench: posix_spawn");
      std::exit(1);
    }
    children.push_back(pid);
  }
  // The sender's CPU over the clients' recording window (they settle first; connecting 64 SDK
  // clients takes a moment, so the window starts a little later and is a little shorter).
  std::this_thread::sleep_for(kSettle + std::chrono::milliseconds(200 + 10 * count));
  const double cpu0 = cpu_seconds();
  const auto wall0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds * 0.8));
  cpu_percent = 100.0 * (cpu_seconds() - cpu0) /
                std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::vector<std::vector<Sample>> out;
  std::int64_t client_cpu_ns = 0;
  std::size_t client_samples = 0;
  for (int i = 0; i < count; ++i) {
    int status = 0;
    waitpid(children[static_cast<std::size_t>(i)], &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      std::fprintf(stderr, "stream_bench: client %d of %s failed\n", i, system.c_str());
    }
    std::vector<Sample> samples;
    std::ifstream in(files[static_cast<std::size_t>(i)], std::ios::binary);
    Sample s;
    while (in.read(reinterpret_cast<char*>(&s), sizeof s)) {
      if (s.deadline_ns == -1) {
        client_cpu_ns += s.kernel_ns;
      } else {
        samples.push_back(s);
      }
    }
    client_samples += samples.size();
    std::remove(files[static_cast<std::size_t>(i)].c_str());
    out.push_back(std::move(samples));
  }
  client_cpu_us_per_sample =
      client_samples == 0 ? 0.0 : 1e-3 * static_cast<double>(client_cpu_ns) / static_cast<double>(client_samples);
  return out;
}

Case summarize(const std::string& system, int count, double seconds,
               const std::vector<std::vector<Sample>>& per_client) {
  Case c;
  c.system = system;
  c.clients = count;
  std::vector<double> rates, age, net, app;
  for (const auto& samples : per_client) {
    rates.push_back(static_cast<double>(samples.size()) / seconds);
    for (const Sample& s : samples) {
      age.push_back(1e-3 * static_cast<double>(s.app_ns - s.deadline_ns));
      if (s.kernel_ns != 0) {
        net.push_back(1e-3 * static_cast<double>(s.kernel_ns - s.deadline_ns));
        app.push_back(1e-3 * static_cast<double>(s.app_ns - s.kernel_ns));
      }
    }
  }
  c.rate_slowest = rates.empty() ? 0.0 : *std::min_element(rates.begin(), rates.end());
  c.rate_median = percentile(rates, 0.5);
  c.p50 = percentile(age, 0.5);
  c.p99 = percentile(age, 0.99);
  c.p999 = percentile(age, 0.999);
  c.net_p50 = percentile(net, 0.5);
  c.net_p99 = percentile(net, 0.99);
  c.app_p50 = percentile(app, 0.5);
  c.app_p99 = percentile(app, 0.99);
  return c;
}

/// hapticd's State sender as the command line sets it (unset: the configuration's defaults).
std::optional<int> sender_cpu, sender_priority;

haptic::v1::ServerConfig server_config(int clients) {
  haptic::v1::ServerConfig config = haptic::config::default_config();
  if (sender_cpu) config.mutable_real_time()->set_sender_cpu(*sender_cpu);
  if (sender_priority) config.mutable_real_time()->set_sender_priority(*sender_priority);
  config.set_grpc_address("127.0.0.1:0");
  config.set_udp_address("127.0.0.1");
  config.set_udp_port(0);
  config.set_status_period_s(0);
  config.set_max_sessions(static_cast<std::uint32_t>(std::max(clients, 64)));
  config.set_max_sessions_per_peer(static_cast<std::uint32_t>(std::max(clients, 64)));
  config.set_session_open_burst_per_peer(static_cast<std::uint32_t>(std::max(clients, 64)));  // one host
  return config;
}

Case run_floor(int count, double seconds) {
  const haptic::v1::ServerConfig config = server_config(count);  // the loop's priority and spin
  // The CPU hapticd's loop would take (and the claim on it, for the floor's run).
  const haptic::runtime::LoopCpuChoice loop_cpu =
      haptic::runtime::choose_loop_cpu(std::nullopt, static_cast<int>(std::thread::hardware_concurrency()));
  FloorSender sender(static_cast<int>(config.real_time().fifo_priority()), loop_cpu.cpu,
                     static_cast<std::int64_t>(config.real_time().spin_us()) * 1000);
  double cpu = 0.0, client_cpu = 0.0;
  const auto samples = run_clients("floor", std::to_string(sender.port()), 0, count, seconds, cpu, client_cpu);
  Case c = summarize("floor", count, seconds, samples);
  c.cpu_percent = cpu;
  c.client_cpu_us = client_cpu;
  c.overruns = sender.overruns();
  return c;
}

Case run_hapticd(int count, double seconds) {
  haptic::app::Server server(server_config(count));
  server.start();
  const std::string address = "127.0.0.1:" + std::to_string(server.grpc_port());
  const std::int64_t origin_ns = monotonic_ns() - server.server_time_ns();
  const std::uint64_t overruns0 = server.stats().overruns();
  double cpu = 0.0, client_cpu = 0.0;
  const auto samples = run_clients("hapticd", address, origin_ns, count, seconds, cpu, client_cpu);
  Case c = summarize("hapticd", count, seconds, samples);
  c.cpu_percent = cpu;
  c.client_cpu_us = client_cpu;
  const haptic::v1::Stats stats = server.stats();
  c.overruns = stats.overruns() - overruns0;
  c.first_send_p50 = stats.send_delay_p50_us();
  c.first_send_p99 = stats.send_delay_p99_us();
  server.shutdown();
  return c;
}

void print_header() {
  std::printf("%7s  %-8s  %15s  %24s  %17s  %17s  %7s  %9s  %8s\n", "clients", "system", "rate slow/med Hz",
              "age p50 / p99 / p99.9 us", "to kernel p50/p99", "to app p50/p99", "CPU %",
              "client us", "overruns");
}

void print_case(const Case& c) {
  char net[32] = "-", app[32] = "-";
  if (c.net_p50 != 0.0 || c.net_p99 != 0.0) {
    std::snprintf(net, sizeof net, "%.0f / %.0f", c.net_p50, c.net_p99);
    std::snprintf(app, sizeof app, "%.0f / %.0f", c.app_p50, c.app_p99);
  }
  std::printf("%7d  %-8s  %7.1f / %5.1f  %8.0f / %6.0f / %6.0f  %17s  %17s  %7.1f  %9.1f  %8llu", c.clients,
              c.system.c_str(), c.rate_slowest, c.rate_median, c.p50, c.p99, c.p999, net, app,
              c.cpu_percent, c.client_cpu_us, static_cast<unsigned long long>(c.overruns));
  if (c.system == "hapticd") {
    std::printf("  (sender: tick -> sendmmsg p50 %.0f / p99 %.0f us)", c.first_send_p50, c.first_send_p99);
  }
  std::printf("\n");
  std::fflush(stdout);
}

std::vector<int> parse_counts(const std::string& text) {
  std::vector<int> counts;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const int n = std::atoi(item.c_str());
    if (n < 1 || n > 256) {
      std::fprintf(stderr, "stream_bench: --clients: each count must be 1 to 256, got \"%s\"\n", item.c_str());
      std::exit(2);
    }
    counts.push_back(n);
  }
  return counts;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 8 && std::strcmp(argv[1], "--client") == 0) {
    const std::string system = argv[2];
    const double seconds = std::atof(argv[5]);
    if (system == "floor") return run_floor_client(static_cast<std::uint16_t>(std::atoi(argv[3])), seconds, argv[6]);
    return run_hapticd_client(argv[3], std::atoll(argv[4]), seconds, argv[6], std::atoi(argv[7]));
  }
  double seconds = 10.0;
  int rounds = 1;
  std::vector<int> counts = {1, 8, 32, 64};
  std::string csv_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--seconds" && has_value) {
      seconds = std::atof(argv[++i]);
    } else if (arg == "--clients" && has_value) {
      counts = parse_counts(argv[++i]);
    } else if (arg == "--rounds" && has_value) {
      rounds = std::atoi(argv[++i]);
    } else if (arg == "--sender-cpu" && has_value) {
      sender_cpu = std::atoi(argv[++i]);
    } else if (arg == "--sender-priority" && has_value) {
      sender_priority = std::atoi(argv[++i]);
    } else if (arg == "--csv" && has_value) {
      csv_path = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: stream_bench [--seconds S=10] [--clients 1,8,32,64] [--rounds R=1] [--csv FILE]\n"
                   "                    [--sender-cpu N] [--sender-priority P]   (hapticd's real_time.sender_*)\n");
      return 2;
    }
  }
  if (!(seconds >= 1.0 && seconds <= 600.0) || rounds < 1 || rounds > 20) {
    std::fprintf(stderr, "stream_bench: --seconds must be 1 to 600 and --rounds 1 to 20\n");
    return 2;
  }
  std::printf("State stream vs a bare UDP floor, loopback, 1 kHz, %.0f s per case, %d round(s); "
              "ages from the tick's deadline\n",
              seconds, rounds);
  print_header();
  std::vector<Case> cases;
  for (int round = 0; round < rounds; ++round) {
    for (const int count : counts) {
      const Case floor = run_floor(count, seconds);
      print_case(floor);
      const Case hapticd = run_hapticd(count, seconds);
      print_case(hapticd);
      std::printf("%7s  %-8s  %15s  %8.2f x / %5.2f x\n", "", "ratio", "", hapticd.p50 / floor.p50,
                  hapticd.p99 / floor.p99);
      cases.push_back(floor);
      cases.push_back(hapticd);
    }
  }
  if (!csv_path.empty()) {
    std::ofstream csv(csv_path);
    csv << "system,clients,rate_slowest_hz,rate_median_hz,age_p50_us,age_p99_us,age_p999_us,"
           "kernel_p50_us,kernel_p99_us,app_p50_us,app_p99_us,cpu_percent,client_cpu_us_per_sample,overruns\n";
    for (const Case& c : cases) {
      csv << c.system << ',' << c.clients << ',' << c.rate_slowest << ',' << c.rate_median << ','
          << c.p50 << ',' << c.p99 << ',' << c.p999 << ',' << c.net_p50 << ',' << c.net_p99 << ','
          << c.app_p50 << ',' << c.app_p99 << ',' << c.cpu_percent << ',' << c.client_cpu_us << ','
          << c.overruns << '\n';
    }
  }
  return 0;
}
