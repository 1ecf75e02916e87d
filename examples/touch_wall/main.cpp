// touch_wall: the smallest program that feels something. It registers a wall (the half-space
// z < 0) and a weak spring field, has the server's simulated hand push the tool into the wall, and
// prints time, hand target, tool height and force at about 20 Hz. On a device with no simulated
// hand (a real one, behind a driver) the hand is the person's: it renders the same wall and prints
// what the tool does for --seconds.
//
// Usage: touch_wall [host:port] [--lockstep] [--hand] [--seconds S]
//                   [--token T | --token-file F] [--ca CA.pem [--cert C.pem --key K.pem]
//                   [--server-name NAME]]
//   --lockstep  the server runs in LOCKSTEP time: this program advances it with Step, and the
//               output is the same on every run.
//   --hand      do not move the simulated hand even where there is one: print what the tool does
//               for --seconds (default 10). The same without a simulated hand (a driver device).
//   --token, --token-file, --ca, --cert, --key, --server-name: a secured server
//               (docs/deployment.md): its bearer token, the CA of its certificate, this client's
//               certificate for mutual TLS, the name its certificate carries.
#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace {

constexpr double kStartZ = 0.02;     // hand target at the start. Unit: m.
constexpr double kEndZ = -0.01;      // 10 mm below the wall's surface. Unit: m.
constexpr double kDescent = 2.0;     // Unit: s.
constexpr double kHold = 1.0;        // Unit: s.
constexpr double kHandStiffness = 200.0;  // Unit: N/m.
constexpr double kHandDamping = 2.0;      // Unit: N·s/m.

double target_at(double t) {
  const double s = t < kDescent ? t / kDescent : 1.0;
  return kStartZ + s * (kEndZ - kStartZ);
}

void print_row(double t, double target, const haptic::State& state) {
  std::printf("%7.3f  %10.2f  %8.3f  %9.3f  %s\n", t, target * 1e3, state.position.z * 1e3,
              state.force.z, state.contact_count > 0 ? "yes" : "no");
}

/// A row without a target: the hand is a person's, or the device's own.
void print_hand_row(double t, const haptic::State& state) {
  std::printf("%7.3f  %10s  %8.3f  %9.3f  %s\n", t, "-", state.position.z * 1e3, state.force.z,
              state.contact_count > 0 ? "yes" : "no");
}

/// The time column in real time: the server's clock from its first row. A restarted server
/// counts from zero again; the rows then carry on from the last one's time instead of going
/// negative. Unit: s.
class RowClock {
 public:
  double at(double server_time) {
    if (!started_) {
      started_ = true;
      first_ = server_time;
    } else if (server_time < last_server_time_) {
      first_ = server_time - last_row_time_;  // a new server: carry on from the last row
    }
    last_server_time_ = server_time;
    last_row_time_ = server_time - first_;
    return last_row_time_;
  }

 private:
  bool started_ = false;
  double first_ = 0.0;  // server time at row time 0 (negative once a restarted server is followed)
  double last_server_time_ = 0.0;
  double last_row_time_ = 0.0;
};

/// Why the server ended this session (an ADMIN's kick, an expired token), once it has; the
/// client does not reconnect after that, so the program must say so and stop.
class SessionEnd {
 public:
  void watch(haptic::Client& client) {
    client.on_connection([this](const haptic::ConnectionChange& change) {
      if (change.state != haptic::ConnectionChange::State::kEnded) return;
      std::lock_guard lock(mutex_);
      reason_ = change.reason.empty() ? "no reason given" : change.reason;
    });
  }
  std::optional<std::string> reason() const {
    std::lock_guard lock(mutex_);
    return reason_;
  }

 private:
  mutable std::mutex mutex_;
  std::optional<std::string> reason_;
};

volatile std::sig_atomic_t interrupted = 0;
void on_interrupt(int) { interrupted = 1; }

int usage_error(const std::string& why) {
  std::fprintf(stderr, "touch_wall: %s\nusage: touch_wall [host:port] [--lockstep] [--hand] [--seconds S] "
                       "[--token T | --token-file F] [--ca CA.pem [--cert C.pem --key K.pem] "
                       "[--server-name NAME]]\n", why.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string address = "127.0.0.1:50051";
  bool lockstep = false;
  bool hand = false;
  double seconds = 10.0;
  haptic::ClientConfig config;
  haptic::TlsOptions tls;
  std::string token_file;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&](std::string& out) {
      if (i + 1 >= argc) return false;
      out = argv[++i];
      return true;
    };
    std::string text;
    if (arg == "--lockstep") {
      lockstep = true;
    } else if (arg == "--hand") {
      hand = true;
    } else if (arg == "--seconds") {
      if (!value(text)) return usage_error("--seconds needs a number");
      char* end = nullptr;
      seconds = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !(seconds > 0.0 && seconds <= 3600.0)) {
        return usage_error("--seconds: '" + text + "' is not a time of 0 to 3600 s");
      }
    } else if (arg == "--token") {
      if (!value(config.token)) return usage_error("--token needs the token");
    } else if (arg == "--token-file") {
      if (!value(token_file)) return usage_error("--token-file needs a file");
    } else if (arg == "--ca") {
      if (!value(tls.ca_file)) return usage_error("--ca needs a PEM file");
    } else if (arg == "--cert") {
      if (!value(tls.cert_file)) return usage_error("--cert needs a PEM file");
    } else if (arg == "--key") {
      if (!value(tls.key_file)) return usage_error("--key needs a PEM file");
    } else if (arg == "--server-name") {
      if (!value(tls.server_name)) return usage_error("--server-name needs a name");
    } else if (arg == "--help" || arg == "-h") {
      std::printf("usage: touch_wall [host:port] [--lockstep] [--hand] [--seconds S] [--token T | "
                  "--token-file F] [--ca CA.pem [--cert C.pem --key K.pem] [--server-name NAME]]\n");
      return 0;
    } else if (arg.rfind("--", 0) == 0) {
      return usage_error("unknown option " + arg);
    } else {
      address = arg;
    }
  }
  if (!token_file.empty()) {
    std::ifstream file(token_file);
    if (!file || !std::getline(file, config.token)) return usage_error("--token-file: cannot read '" + token_file + "'");
  }
  if (!tls.ca_file.empty()) {
    config.tls = tls;
  } else if (!tls.cert_file.empty() || !tls.key_file.empty() || !tls.server_name.empty()) {
    return usage_error("--cert, --key and --server-name need --ca (TLS)");
  }
  SessionEnd session_end;  // before the client, so it outlives every callback the client makes
  try {
    config.server_address = address;
    config.client_name = "touch_wall";
    haptic::Client client(config);
    session_end.watch(client);
    const double rate = client.device_info().loop_rate_hz;
    const auto ticks_per_row = static_cast<std::uint32_t>(rate / 20.0);  // ~20 Hz output
    client.subscribe(ticks_per_row);

    auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1},
                                 .impedance = {.stiffness = 1000.0, .damping = 1.0}});
    if (hand || !client.device_info().simulated) {
      // No simulated hand to move (a real device), or asked not to: the wall is the person's to
      // touch, or whatever the device's own hand does. Print what the tool does until --seconds
      // have passed or Ctrl-C.
      std::signal(SIGINT, on_interrupt);
      std::signal(SIGTERM, on_interrupt);
      std::printf("touch_wall: %s at %.0f Hz, %s time, %s; wall z < 0 with K = 1000 N/m, B = 1 N*s/m: "
                  "push the tool down into it (%.0f s, Ctrl-C ends)\n",
                  client.device_info().name.c_str(), rate, lockstep ? "lockstep" : "real",
                  client.device_info().simulated ? "the simulated hand left still" : "no simulated hand",
                  seconds);
      std::printf("%7s  %10s  %8s  %9s  %s\n", "time_s", "target_mm", "z_mm", "force_N", "contact");
      haptic::State state;
      double deepest_mm = 0.0, strongest_n = 0.0;
      const auto note = [&](double t) {
        print_hand_row(t, state);
        deepest_mm = std::min(deepest_mm, state.position.z * 1e3);
        strongest_n = std::max(strongest_n, state.force.z);
      };
      if (lockstep) {  // the device's own dynamics, stepped: the same rows on every run
        const auto ticks_per_step = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(rate / 100.0));
        std::optional<std::uint64_t> first_tick;
        std::uint64_t next_row_tick = 0;
        for (double t = 0.0; interrupted == 0 && t < seconds;) {
          const std::uint64_t tick = client.step(ticks_per_step);
          if (!first_tick) {
            first_tick = tick;
            next_row_tick = tick;
          }
          t = static_cast<double>(tick - *first_tick + ticks_per_step) / rate;
          if (tick >= next_row_tick && client.wait_for_tick(tick, state, std::chrono::seconds(2))) {
            note(t);
            next_row_tick = tick + ticks_per_row;
          }
        }
      } else {
        RowClock clock;
        const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (interrupted == 0 && std::chrono::steady_clock::now() < end) {
          if (const auto ended = session_end.reason()) {
            std::fprintf(stderr, "touch_wall: the server ended this session: %s\n", ended->c_str());
            return 1;
          }
          if (!client.poll_state(state, std::chrono::milliseconds(100))) continue;
          note(clock.at(state.server_time));
        }
      }
      std::printf("touch_wall: done; deepest %.3f mm into the wall, largest push back %.3f N, %llu "
                  "datagrams received\n", -deepest_mm, strongest_n,
                  static_cast<unsigned long long>(client.receive_counters().accepted));
      return 0;
    }
    auto spring = client.add_spring_field(
        {.anchor = {0, 0, kStartZ}, .stiffness = 20.0, .damping = 0.0, .max_force = 2.0});

    std::printf("touch_wall: %s at %.0f Hz, %s time; wall z < 0 with K = 1000 N/m, B = 1 N*s/m\n",
                client.device_info().name.c_str(), rate, lockstep ? "lockstep" : "real");
    std::printf("%7s  %10s  %8s  %9s  %s\n", "time_s", "target_mm", "z_mm", "force_N", "contact");

    const double duration = kDescent + kHold;
    haptic::State state;
    std::uint64_t last_tick = 0;  // lockstep: the tick our last Step ended on
    if (lockstep) {
      // Advance the server in 10 ms steps, moving the hand's target between steps. Rows are
      // timed from our first step: the server's tick count may not start at zero.
      const auto ticks_per_step = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(rate / 100.0));
      std::optional<std::uint64_t> first_tick;  // the tick our first Step ended on
      std::uint64_t next_row_tick = 0;
      double t = 0.0;
      while (t < duration) {
        const double target = target_at(t);
        client.set_operator(haptic::OperatorInput::follow({0, 0, target}, kHandStiffness,
                                                          kHandDamping));
        const std::uint64_t tick = client.step(ticks_per_step);
        last_tick = tick;
        if (!first_tick) {
          first_tick = tick;
          next_row_tick = tick;
        }
        t = static_cast<double>(tick - *first_tick + ticks_per_step) / rate;
        // The Step reply carries the tick's state, so this returns at once.
        if (tick >= next_row_tick && client.wait_for_tick(tick, state, std::chrono::seconds(2))) {
          print_row(t, target, state);
          next_row_tick = tick + ticks_per_row;
        }
      }
    } else {
      const auto start = std::chrono::steady_clock::now();
      auto next_update = start;
      double t = 0.0;
      RowClock clock;
      while (t < duration) {
        t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        client.set_operator(haptic::OperatorInput::follow({0, 0, target_at(t)}, kHandStiffness,
                                                          kHandDamping));
        if (client.poll_state(state, std::chrono::milliseconds(0))) {
          print_row(clock.at(state.server_time), target_at(t), state);
        }
        next_update += std::chrono::milliseconds(10);
        std::this_thread::sleep_until(next_update);
      }
    }
    client.set_operator(haptic::OperatorInput::release());
    if (lockstep) {
      // Only what lockstep makes exact: how many State datagrams have arrived by now depends on
      // the network's timing, so it would differ between runs that are otherwise the same.
      std::printf("touch_wall: done; server at tick %llu\n", static_cast<unsigned long long>(last_tick));
    } else {
      try {
        const haptic::Stats stats = client.stats();
        std::printf("touch_wall: done; server loop %.1f Hz, lateness p99 %.0f us, %llu datagrams received\n",
                    stats.achieved_rate_hz, stats.lateness_p99_us,
                    static_cast<unsigned long long>(client.receive_counters().accepted));
      } catch (const haptic::PermissionDeniedError&) {  // the loop's figures are an ADMIN's
        std::printf("touch_wall: done; %llu datagrams received\n",
                    static_cast<unsigned long long>(client.receive_counters().accepted));
      }
    }
  } catch (const haptic::ConnectionError& error) {
    // Starting a server is the fix only when nothing listens; a TLS or token mismatch says its own.
    const bool nothing_listens = std::strstr(error.what(), "nothing listens") != nullptr;
    std::fprintf(stderr, "touch_wall: %s%s\n", error.what(),
                 nothing_listens ? ". Start one with ./scripts/run" : "");
    return 1;
  } catch (const haptic::InvalidArgumentError& error) {
    std::fprintf(stderr, "touch_wall: %s\n", error.what());  // the options given (a token in clear, ...)
    return 2;
  } catch (const haptic::Error& error) {
    std::fprintf(stderr, "touch_wall: %s\n", error.what());
    return 1;
  }
  return 0;
}
