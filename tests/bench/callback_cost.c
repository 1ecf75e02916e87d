/* The C side of callback_cost_bench (a process of its own: libhaptic_c carries its own copy of the
 * SDK and of the protocol's generated code, which one process cannot register twice next to
 * haptic::sdk). Connects to hapticd (first argument) for the seconds given and prints, one per
 * line, each State's time from the kernel's receive stamp to the first line of its callback (µs). */
#define _POSIX_C_SOURCE 200809L

#include <haptic/haptic_c.h>

#include <pthread.h>
#include <sys/resource.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define MAX_SAMPLES 200000

typedef struct delays {
  pthread_mutex_t lock;
  size_t count;
  unsigned long long calls;
  double us[MAX_SAMPLES];
} delays;

static double cpu_seconds(void) {
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return (double)(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         (double)(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

static unsigned long long calls_of(delays* d) {
  unsigned long long calls;
  pthread_mutex_lock(&d->lock);
  calls = d->calls;
  pthread_mutex_unlock(&d->lock);
  return calls;
}

static void on_state(const haptic_state* state, void* user) {
  const int64_t now = haptic_steady_clock_ns();
  delays* d = (delays*)user;
  pthread_mutex_lock(&d->lock);
  ++d->calls;
  if (state->arrived_at_ns != 0 && d->count < MAX_SAMPLES) d->us[d->count++] = (double)(now - state->arrived_at_ns) * 1e-3;
  pthread_mutex_unlock(&d->lock);
}

int main(int argc, char** argv) {
  static delays d;
  haptic_client_config config;
  haptic_client* client = NULL;
  haptic_error err;
  struct timespec wait, warm_up = {0, 500000000L};
  double seconds, cpu;
  unsigned long long calls;
  size_t i;
  if (argc < 3) {
    fprintf(stderr, "usage: callback_cost_c host:port seconds\n");
    return 2;
  }
  seconds = atof(argv[2]);
  pthread_mutex_init(&d.lock, NULL);
  haptic_client_config_init(&config);
  config.server_address = argv[1];
  config.client_name = "callback-cost-c";
  if (haptic_client_open(&config, &client, &err) != HAPTIC_OK) {
    fprintf(stderr, "callback_cost_c: %s\n", err.message);
    return 1;
  }
  haptic_client_on_state(client, on_state, &d, &err);
  nanosleep(&warm_up, NULL);
  calls = calls_of(&d);
  cpu = cpu_seconds();
  wait.tv_sec = (time_t)seconds;
  wait.tv_nsec = (long)((seconds - (double)wait.tv_sec) * 1e9);
  nanosleep(&wait, NULL);
  cpu = cpu_seconds() - cpu;
  calls = calls_of(&d) - calls;
  haptic_client_on_state(client, NULL, NULL, &err);
  haptic_client_close(client, &err);
  printf("cpu_us_per_sample %.3f samples %llu\n", calls > 0 ? cpu * 1e6 / (double)calls : 0.0, calls);
  for (i = 0; i < d.count; ++i) printf("%.3f\n", d.us[i]);
  return 0;
}
