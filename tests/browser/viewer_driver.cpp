// The browser test's client (web/test/viewer.test.mjs): a session on the hapticd at argv[1] that
// registers one object of every shape and one field of every kind through the SDK, prints what it
// registered as one JSON line, then moves the simulated operator on command, one line each:
//   move X Y Z TICKS   the hand pulls the tool towards (X, Y, Z) m; lockstep: step TICKS and print
//                      the last tick and the tool's position
//   sway               real time: the hand's target swings ±40 mm along x at 0.5 Hz
//   quit
#include <haptic/haptic.hpp>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "support/every_kind_scene.hpp"

namespace {

/// [{"id": "7", "kind": "sphere"}, ...]: ids as strings, as the viewer's JSON has them.
template <typename Handle>
std::string listed(const std::vector<Handle>& items, const std::vector<std::string>& kinds) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i == 0 ? "" : ", ") + std::string("{\"id\": \"") + std::to_string(items[i].id()) +
           "\", \"kind\": \"" + kinds[i] + "\"}";
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: viewer_driver HOST:PORT\n");
    return 2;
  }
  try {
    haptic::ClientConfig config;
    config.server_address = argv[1];
    config.client_name = "browser-test";
    haptic::Client client(config);
    const haptic::test::EveryKind registered = haptic::test::register_every_kind(client);
    std::printf("{\"session\": \"%llu\", \"objects\": [%s], \"fields\": [%s]}\n",
                static_cast<unsigned long long>(client.session_id()),
                listed(registered.objects, registered.object_kinds).c_str(),
                listed(registered.fields, registered.field_kinds).c_str());
    std::fflush(stdout);
    for (std::string line; std::getline(std::cin, line);) {
      std::istringstream words(line);
      std::string command;
      words >> command;
      if (command == "quit") break;
      if (command == "move") {
        double x = 0, y = 0, z = 0;
        std::uint32_t ticks = 0;
        words >> x >> y >> z >> ticks;
        client.set_operator(haptic::OperatorInput::follow({x, y, z}, 200.0, 5.0));
        const std::uint64_t tick = client.step(ticks);
        haptic::State state;
        client.wait_for_tick(tick, state, std::chrono::seconds(5));
        std::printf("{\"tick\": \"%llu\", \"position\": [%.17g, %.17g, %.17g]}\n",
                    static_cast<unsigned long long>(state.tick), state.position.x, state.position.y,
                    state.position.z);
      } else if (command == "sway") {
        haptic::OperatorInput input = haptic::OperatorInput::follow({0.0, 0.0, 0.0}, 200.0, 5.0);
        input.path.shape = haptic::OperatorInput::Path::Shape::kSine;
        input.path.amplitude = {0.04, 0.0, 0.0};
        input.path.frequency_hz = 0.5;
        client.set_operator(input);
        std::printf("{\"swaying\": true}\n");
      } else {
        std::printf("{\"error\": \"unknown command '%s'\"}\n", command.c_str());
      }
      std::fflush(stdout);
    }
  } catch (const haptic::Error& error) {
    std::fprintf(stderr, "viewer_driver: %s\n", error.what());
    return 1;
  }
  return 0;
}
