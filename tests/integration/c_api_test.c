/* The C API from C99 against a real lockstep hapticd (address from c_api_test_main.cpp): a wall
 * holds the operator's push, its removal lets go, and a bad wall is refused naming the field. */
#include "integration/c_api_test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "haptic/haptic_c.h"

#define CHECK(cond)                                                   \
  do {                                                                \
    if (!(cond)) {                                                    \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      failures++;                                                     \
    }                                                                 \
  } while (0)

static int step_and_get(haptic_client* client, uint32_t ticks, haptic_state* out) {
  haptic_error err;
  uint64_t last = 0;
  if (haptic_client_step(client, ticks, &last, &err) != HAPTIC_OK) {
    fprintf(stderr, "step: %s\n", err.message);
    return -1;
  }
  out->size = sizeof(*out);
  if (haptic_client_wait_for_tick(client, last, out, 5000, &err) != HAPTIC_OK) {
    fprintf(stderr, "wait_for_tick: %d %s\n", err.code, err.message);
    return -1;
  }
  return out->tick == last ? 0 : -1;
}

int c_api_test_run(const char* address) {
  int failures = 0;
  haptic_error err;
  haptic_client_config config;
  haptic_client* client = NULL;
  haptic_wall_spec wall;
  haptic_object* object = NULL;
  haptic_object* refused = NULL;
  haptic_state s;
  haptic_vec3 push = {0.0, 0.0, -5.0};

  CHECK(haptic_c_version() == HAPTIC_C_VERSION);

  haptic_client_config_init(&config);
  CHECK(config.size == sizeof(config));
  CHECK(strcmp(config.server_address, "127.0.0.1:50051") == 0);
  config.server_address = address;
  config.client_name = "c-api-test";
  config.heartbeat_period_ms = 20;
  if (haptic_client_open(&config, &client, &err) != HAPTIC_OK) {
    fprintf(stderr, "open: %d %s\n", err.code, err.message);
    return 1;
  }
  CHECK(err.code == HAPTIC_OK && err.message[0] == '\0');

  /* The horizontal wall through the origin; the operator pushes 5 N down into it. */
  haptic_wall_spec_init(&wall);
  CHECK(wall.size == sizeof(wall) && wall.normal.z == 1.0);
  wall.stiffness = 1000.0;
  wall.damping = 1.0;
  CHECK(haptic_client_add_wall(client, &wall, &object, &err) == HAPTIC_OK);
  CHECK(object != NULL);
  CHECK(haptic_client_set_operator_push(client, push, &err) == HAPTIC_OK);
  CHECK(step_and_get(client, 3000, &s) == 0);
  /* At rest the wall balances the push: 5 mm deep, 5 N up. */
  CHECK(s.contact_count == 1u);
  CHECK(fabs(s.position.z + 0.005) < 1e-6);
  CHECK(fabs(s.force.z - 5.0) < 1e-3);
  CHECK(fabs(s.force.x) < 1e-12 && fabs(s.force.y) < 1e-12);

  /* Removed, the force ramps out and is zero after. */
  CHECK(haptic_object_remove(object, &err) == HAPTIC_OK);
  CHECK(step_and_get(client, 100, &s) == 0);
  CHECK(s.force.z == 0.0 && s.contact_count == 0u);

  /* poll_state: nothing newer than the step's sample arrives while the server stands still. */
  s.size = sizeof(s);
  {
    const int polled = haptic_client_poll_state(client, &s, 50, &err);
    CHECK(polled == HAPTIC_OK || polled == HAPTIC_TIMEOUT);
  }

  /* A bad wall is refused naming the field, and makes nothing. */
  haptic_wall_spec_init(&wall);
  wall.normal.z = NAN;
  wall.stiffness = 1000.0;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(err.code == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strncmp(err.message, "CreateObject: object.half_space.normal", 38) == 0);
  CHECK(refused == NULL);
  haptic_wall_spec_init(&wall);
  wall.stiffness = -1.0;
  CHECK(haptic_client_add_wall(client, &wall, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  CHECK(strncmp(err.message, "CreateObject: object.impedance.stiffness: must be >= 0", 54) == 0);
  CHECK(refused == NULL);
  /* Nothing was made: the tool falls freely under the push. */
  CHECK(step_and_get(client, 10, &s) == 0);
  CHECK(s.contact_count == 0u && s.force.z == 0.0);

  /* No exception crosses: a NULL argument is a code. */
  CHECK(haptic_client_add_wall(client, NULL, &refused, &err) == HAPTIC_ERROR_INVALID_ARGUMENT);
  if (failures > 0) fprintf(stderr, "last error: %d %s\n", err.code, err.message);

  haptic_client_close(client);
  return failures;
}
