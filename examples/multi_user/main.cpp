// multi_user: two users, each on their own device port of one hapticd, push one shared virtual
// mass together, and a third client watches. User A (port 0) places a 100 g box on a viscous
// floor (000 eq. 7.1: f = m Ẍ + B Ẋ, B = 4 N·s/m) in front of both tools; the server's simulated
// hands push both tools along +x, A with 0.10 N and B with 0.15 N. The watcher reads where the box
// is (object_states) and its own state stream, and prints the box's position and speed against
// time next to the speed eq. 7.1 predicts once tools and box move together:
//   v = (F_A + F_B) / (B + b_A + b_B), b_A and b_B the devices' own damping.
//
// Usage: multi_user [host:port] [--lockstep]
//   against hapticd --config config/multi_user.json (two point-mass devices; port 1 is an extra
//   device). --lockstep: the server runs in LOCKSTEP time and the watcher advances it with Step.
#include <haptic/haptic.hpp>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr double kForceA = 0.10;       // user A's push. Unit: N.
constexpr double kForceB = 0.15;       // user B's push. Unit: N.
constexpr double kBoxMass = 0.1;       // Unit: kg.
constexpr double kBoxDamping = 4.0;    // B, the floor's viscous friction. Unit: N·s/m.
constexpr double kDuration = 1.0;      // Unit: s.
constexpr double kRowPeriod = 0.05;    // Unit: s.

haptic::ClientConfig config_for(const std::string& address, const char* name,
                                std::uint32_t device_index, std::uint32_t decimation) {
  haptic::ClientConfig config;
  config.server_address = address;
  config.client_name = name;
  config.device_index = device_index;
  config.state_decimation = decimation;
  return config;
}

/// The box's state as the watcher sees it, or nullopt before it is in the scene.
std::optional<haptic::ObjectState> find_box(haptic::Client& watcher, std::uint64_t id) {
  for (const haptic::ObjectState& object : watcher.object_states()) {
    if (object.id == id) return object;
  }
  return std::nullopt;
}

void print_row(double t, const haptic::ObjectState& box, const haptic::State& tool_a,
               const haptic::State& tool_b) {
  std::printf("%7.3f  %9.2f  %11.2f  %9.2f  %9.2f\n", t, box.position.x * 1e3,
              box.velocity.x * 1e3, tool_a.position.x * 1e3, tool_b.position.x * 1e3);
}

}  // namespace

int main(int argc, char** argv) {
  std::string address = "127.0.0.1:50051";
  bool lockstep = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--lockstep") == 0) {
      lockstep = true;
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf("usage: multi_user [host:port] [--lockstep]\n");
      return 0;
    } else {
      address = argv[i];
    }
  }

  try {
    haptic::Client user_a(config_for(address, "multi_user A", 0, 0));
    // B streams its own port's state every tick (A's port is the watcher's).
    haptic::Client user_b(config_for(address, "multi_user B", 1, 1));
    const double rate = user_a.device_info().loop_rate_hz;
    const auto ticks_per_row = static_cast<std::uint32_t>(rate * kRowPeriod);
    haptic::Client watcher(config_for(address, "multi_user watcher", 0, ticks_per_row));

    // The box's -x face at x = 15 mm, wide enough in y for both tools (20 mm apart).
    auto box = user_a.add_box({.pose = {.position = {0.02, 0.0, 0.02}},
                               .half_extents = {0.005, 0.03, 0.01},
                               .impedance = {.stiffness = 1000.0, .damping = 2.0},
                               .dynamics = {.mass = kBoxMass, .damping = kBoxDamping}});
    // Both devices are Eom et al.'s point mass, b = 0.022 N·s/m each (config/multi_user.json).
    const double b_devices = 2 * 0.022;
    const double v_predicted = (kForceA + kForceB) / (kBoxDamping + b_devices);
    std::printf("multi_user: port 0 %s, port 1 %s, %.0f Hz, %s time\n",
                user_a.device_info().name.c_str(), user_b.device_info().name.c_str(), rate,
                lockstep ? "lockstep" : "real");
    std::printf("multi_user: box m = %.2f kg, B = %.1f N*s/m; pushes %.2f N + %.2f N; eq. 7.1 "
                "speed (F_A + F_B) / (B + b_A + b_B) = %.2f mm/s\n",
                kBoxMass, kBoxDamping, kForceA, kForceB, v_predicted * 1e3);
    std::printf("%7s  %9s  %11s  %9s  %9s\n", "time_s", "box_x_mm", "box_v_mm_s", "tool_A_mm",
                "tool_B_mm");

    user_a.set_operator(haptic::OperatorInput::push({kForceA, 0, 0}));
    user_b.set_operator(haptic::OperatorInput::push({kForceB, 0, 0}));

    haptic::State tool_a;  // port 0's tool, from the watcher's stream (it shares A's port)
    haptic::State tool_b;  // port 1's tool, from B's own state stream
    std::optional<haptic::ObjectState> last;
    if (lockstep) {
      std::optional<std::uint64_t> first_tick;
      double t = 0.0;
      while (t < kDuration - 1e-9) {
        const std::uint64_t tick = watcher.step(ticks_per_row);
        if (!first_tick) first_tick = tick - ticks_per_row;
        t = static_cast<double>(tick - *first_tick) / rate;
        // The Step reply carries port 0's state; B's datagram for the same tick is on its way.
        (void)watcher.wait_for_tick(tick, tool_a, std::chrono::seconds(2));
        (void)user_b.wait_for_tick(tick, tool_b, std::chrono::seconds(2));
        last = find_box(watcher, box.id());
        if (last) print_row(t, *last, tool_a, tool_b);
      }
    } else {
      const auto start = std::chrono::steady_clock::now();
      auto next_row = start;
      double t = 0.0;
      while (t < kDuration) {
        next_row += std::chrono::milliseconds(static_cast<int>(kRowPeriod * 1e3));
        std::this_thread::sleep_until(next_row);
        t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        (void)watcher.poll_state(tool_a, std::chrono::milliseconds(0));
        (void)user_b.poll_state(tool_b, std::chrono::milliseconds(0));
        last = find_box(watcher, box.id());
        if (last) print_row(t, *last, tool_a, tool_b);
      }
    }
    user_a.set_operator(haptic::OperatorInput::release());
    user_b.set_operator(haptic::OperatorInput::release());
    if (last) {
      std::printf("multi_user: done; box speed %.2f mm/s against %.2f mm/s predicted\n",
                  last->velocity.x * 1e3, v_predicted * 1e3);
    }
  } catch (const haptic::ConnectionError& error) {
    const bool nothing_listens = std::strstr(error.what(), "nothing listens") != nullptr;
    std::fprintf(stderr, "multi_user: %s%s\n", error.what(),
                 nothing_listens ? ". Start one with ./scripts/run --config config/multi_user.json" : "");
    return 1;
  } catch (const haptic::Error& error) {
    std::fprintf(stderr, "multi_user: %s\n", error.what());
    return 1;
  }
  return 0;
}
