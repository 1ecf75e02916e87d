// Links against the installed SDK and tries to connect to a server that is not there: proves the
// headers, the library and its dependencies resolve, and that the error is a typed one.
#include <haptic/haptic.hpp>

#include <chrono>
#include <cstdio>

int main() {
  haptic::ClientConfig config;
  config.server_address = "127.0.0.1:1";  // nothing listens on port 1
  config.rpc_timeout = std::chrono::milliseconds(300);
  try {
    haptic::Client client(config);
  } catch (const haptic::ConnectionError& error) {
    std::printf("consumer: got ConnectionError as expected: %s\n", error.what());
    return 0;
  }
  std::printf("consumer: expected a ConnectionError\n");
  return 1;
}
