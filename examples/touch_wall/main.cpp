// touch_wall: the smallest program that feels something. It registers a wall (the half-space
// z < 0) and a weak spring field, has the server's simulated hand push the tool into the wall, and
// prints time, hand target, tool height and force at about 20 Hz.
//
// Usage: touch_wall [host:port] [--lockstep]
//   --lockstep  the server runs in LOCKSTEP time: this program advances it with Step, and the
//               output is the same on every run.
#include <haptic/haptic.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
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

}  // namespace

int main(int argc, char** argv) {
  std::string address = "127.0.0.1:50051";
  bool lockstep = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--lockstep") == 0) {
      lockstep = true;
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf("usage: touch_wall [host:port] [--lockstep]\n");
      return 0;
    } else {
      address = argv[i];
    }
  }

  try {
    haptic::ClientConfig config;
    config.server_address = address;
    config.client_name = "touch_wall";
    haptic::Client client(config);
    const double rate = client.device_info().loop_rate_hz;
    const auto ticks_per_row = static_cast<std::uint32_t>(rate / 20.0);  // ~20 Hz output
    client.subscribe(ticks_per_row);

    auto wall = client.add_wall({.point = {0, 0, 0}, .normal = {0, 0, 1},
                                 .impedance = {.stiffness = 1000.0, .damping = 1.0}});
    auto spring = client.add_spring_field(
        {.anchor = {0, 0, kStartZ}, .stiffness = 20.0, .damping = 0.0, .max_force = 2.0});

    std::printf("touch_wall: %s at %.0f Hz, %s time; wall z < 0 with K = 1000 N/m, B = 1 N*s/m\n",
                client.device_info().name.c_str(), rate, lockstep ? "lockstep" : "real");
    std::printf("%7s  %10s  %8s  %9s  %s\n", "time_s", "target_mm", "z_mm", "force_N", "contact");

    const double duration = kDescent + kHold;
    haptic::State state;
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
      double first_server_time = -1.0;
      while (t < duration) {
        t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        client.set_operator(haptic::OperatorInput::follow({0, 0, target_at(t)}, kHandStiffness,
                                                          kHandDamping));
        if (client.poll_state(state, std::chrono::milliseconds(0))) {
          if (first_server_time < 0) first_server_time = state.server_time;
          print_row(state.server_time - first_server_time, target_at(t), state);
        }
        next_update += std::chrono::milliseconds(10);
        std::this_thread::sleep_until(next_update);
      }
    }
    client.set_operator(haptic::OperatorInput::release());
    const haptic::Stats stats = client.stats();
    if (lockstep) {
      std::printf("touch_wall: done; server at tick %llu, %llu datagrams received\n",
                  static_cast<unsigned long long>(stats.ticks),
                  static_cast<unsigned long long>(client.receive_counters().accepted));
    } else {
      std::printf("touch_wall: done; server loop %.1f Hz, lateness p99 %.0f us, %llu datagrams received\n",
                  stats.achieved_rate_hz, stats.lateness_p99_us,
                  static_cast<unsigned long long>(client.receive_counters().accepted));
    }
  } catch (const haptic::ConnectionError& error) {
    std::fprintf(stderr, "touch_wall: cannot reach hapticd at %s (%s). Is it running? "
                         "Start it with ./scripts/run\n", address.c_str(), error.what());
    return 1;
  } catch (const haptic::Error& error) {
    std::fprintf(stderr, "touch_wall: %s\n", error.what());
    return 1;
  }
  return 0;
}
