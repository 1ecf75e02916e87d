// Links the installed session recorder (haptic::recorder, with the HDF5 the package finds again):
// a recorder of a Client that could not connect is never made, but its code must link.
#include <haptic/haptic.hpp>
#include <haptic/recorder.hpp>

#include <chrono>
#include <cstdio>

int main() {
  haptic::ClientConfig config;
  config.server_address = "127.0.0.1:1";  // nothing listens on port 1
  config.rpc_timeout = std::chrono::milliseconds(300);
  try {
    haptic::Client client(config);
    haptic::Recorder recorder(client, {.path = "never.h5"});
    std::printf("recorder_consumer: %llu samples\n",
                static_cast<unsigned long long>(recorder.close().samples_written));
  } catch (const haptic::ConnectionError&) {
    std::printf("recorder_consumer: linked; ConnectionError as expected\n");
    return 0;
  }
  return 1;
}
