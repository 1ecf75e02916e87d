/* A driver built against a future driver ABI (version + 1, a reading struct that grew): hapticd
 * must refuse it before calling anything but the entry, naming both versions. */
#include <haptic/driver.h>

#include <stddef.h>

static void* create(const char* params, char* error) {
  (void)params;
  (void)error;
  return NULL;  /* never reached: the version check comes first */
}

static const haptic_driver_api kApi = {
    HAPTIC_DRIVER_ABI_VERSION + 1u,
    sizeof(haptic_driver_info),
    sizeof(haptic_driver_reading) + 16u,
    sizeof(haptic_driver_command),
    create, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
};

const haptic_driver_api* haptic_driver_entry(void) { return &kApi; }
