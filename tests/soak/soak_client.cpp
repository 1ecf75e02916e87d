// A client to be killed or stopped by the soak tests: it registers a stiff wall under the tool and
// has the simulated hand press into it, prints "ready", then keeps its session alive (the SDK's
// heartbeats) until it is killed. Usage: soak_client HOST:PORT
#include <haptic/haptic.hpp>

#include <chrono>
#include <cstdio>
#include <thread>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: soak_client HOST:PORT\n");
    return 2;
  }
  try {
    haptic::ClientConfig config;
    config.server_address = argv[1];
    config.client_name = "soak-wall";
    config.state_decimation = 0;
    haptic::Client client(config);
    haptic::ObjectHandle wall =
        client.add_wall(haptic::WallSpec{{0, 0, 0}, {0, 0, 1}, {1000.0, 1.0}});
    client.set_operator(haptic::OperatorInput::follow({0, 0, -0.01}, 800.0, 15.0));
    std::printf("ready\n");
    std::fflush(stdout);
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  } catch (const haptic::Error& error) {
    std::fprintf(stderr, "soak_client: %s\n", error.what());
    return 1;
  }
}
