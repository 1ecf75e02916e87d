/* Links the installed C API: the library's version is the header's, and a server that is not
 * there is HAPTIC_ERROR_CONNECTION with the SDK's message, nothing thrown. */
#include <haptic/haptic_c.h>

#include <stdio.h>

int main(void) {
  haptic_client_config config;
  haptic_client* client = NULL;
  haptic_error err;
  if (haptic_c_version() != HAPTIC_C_VERSION) {
    printf("c_consumer: library version %u, header %u\n", haptic_c_version(), HAPTIC_C_VERSION);
    return 1;
  }
  haptic_client_config_init(&config);
  config.server_address = "127.0.0.1:1"; /* nothing listens on port 1 */
  config.rpc_timeout_ms = 300;
  if (haptic_client_open(&config, &client, &err) != HAPTIC_ERROR_CONNECTION || client != NULL) {
    printf("c_consumer: expected a connection error, got %d %s\n", err.code, err.message);
    return 1;
  }
  printf("c_consumer: linked; HAPTIC_ERROR_CONNECTION as expected (%s)\n", err.message);
  return 0;
}
