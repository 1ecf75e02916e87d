/* touch_wall in C: what examples/touch_wall/main.cpp does, over the C API (haptic/haptic_c.h),
 * printing the same lines. It registers a wall (the half-space z < 0) and a weak spring field, has
 * the server's simulated hand push the tool into the wall, and prints time, hand target, tool
 * height and force at about 20 Hz. On a device with no simulated hand it renders the same wall and
 * prints what the tool does for --seconds.
 *
 * Usage: touch_wall_c [host:port] [--lockstep] [--hand] [--seconds S]
 *                     [--token T | --token-file F] [--ca CA.pem [--cert C.pem --key K.pem]
 *                     [--server-name NAME]]
 * Build against the installed package: cc touch_wall.c -lhaptic_c -lm */
#define _POSIX_C_SOURCE 200809L

#include <haptic/haptic_c.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define START_Z 0.02          /* hand target at the start. Unit: m */
#define END_Z (-0.01)         /* 10 mm below the wall's surface. Unit: m */
#define DESCENT 2.0           /* Unit: s */
#define HOLD 1.0              /* Unit: s */
#define HAND_STIFFNESS 200.0  /* Unit: N/m */
#define HAND_DAMPING 2.0      /* Unit: N·s/m */
#define USAGE                                                                                   \
  "touch_wall [host:port] [--lockstep] [--hand] [--seconds S] [--token T | --token-file F] "  \
  "[--ca CA.pem [--cert C.pem --key K.pem] [--server-name NAME]]"

static double target_at(double t) {
  const double s = t < DESCENT ? t / DESCENT : 1.0;
  return START_Z + s * (END_Z - START_Z);
}

static void print_row(double t, double target, const haptic_state* state) {
  printf("%7.3f  %10.2f  %8.3f  %9.3f  %s\n", t, target * 1e3, state->position.z * 1e3,
         state->force.z, state->contact_count > 0 ? "yes" : "no");
}

/* The time column in real time: the server's clock from its first row. A restarted server counts
 * from zero again; the rows then carry on from the last one's time instead of going negative.
 * Unit: s. */
typedef struct row_clock {
  int started;
  double first;  /* server time at row time 0 */
  double last_server_time;
  double last_row_time;
} row_clock;

static double row_clock_at(row_clock* clock, double server_time) {
  if (!clock->started) {
    clock->started = 1;
    clock->first = server_time;
  } else if (server_time < clock->last_server_time) {
    clock->first = server_time - clock->last_row_time; /* a new server: carry on */
  }
  clock->last_server_time = server_time;
  clock->last_row_time = server_time - clock->first;
  return clock->last_row_time;
}

/* A row without a target: the hand is a person's, or the device's own. */
static void print_hand_row(double t, const haptic_state* state) {
  printf("%7.3f  %10s  %8.3f  %9.3f  %s\n", t, "-", state->position.z * 1e3, state->force.z,
         state->contact_count > 0 ? "yes" : "no");
}

static volatile sig_atomic_t interrupted = 0;
static void on_interrupt(int signal_number) {
  (void)signal_number;
  interrupted = 1;
}

static int usage_error(const char* why, const char* what) {
  fprintf(stderr, "touch_wall: %s%s\nusage: " USAGE "\n", why, what);
  return 2;
}

static double now_s(void) { return (double)haptic_steady_clock_ns() * 1e-9; }

static void sleep_until_s(double t) {
  const double left = t - now_s();
  if (left > 0) {
    struct timespec ts;
    ts.tv_sec = (time_t)left;
    ts.tv_nsec = (long)((left - (double)ts.tv_sec) * 1e9);
    nanosleep(&ts, NULL);
  }
}

/* The exit status for a failed call, as the C++ example maps its exceptions. */
static int failed(const haptic_error* err) {
  if (err->code == HAPTIC_ERROR_CONNECTION) {
    /* Starting a server is the fix only when nothing listens; a TLS or token mismatch says its own. */
    fprintf(stderr, "touch_wall: %s%s\n", err->message,
            strstr(err->message, "nothing listens") != NULL ? ". Start one with ./scripts/run" : "");
    return 1;
  }
  fprintf(stderr, "touch_wall: %s\n", err->message);
  return err->code == HAPTIC_ERROR_INVALID_ARGUMENT ? 2 : 1;
}

/* The device's own hand (or a person's): print what the tool does for `seconds`. */
static int watch(haptic_client* client, const haptic_device_info* info, int lockstep,
                 double seconds, haptic_error* err) {
  const double rate = info->loop_rate_hz;
  const uint32_t ticks_per_row = (uint32_t)(rate / 20.0);
  haptic_state state;
  haptic_receive_counters counters;
  double deepest_mm = 0.0, strongest_n = 0.0;
  signal(SIGINT, on_interrupt);
  signal(SIGTERM, on_interrupt);
  printf("touch_wall: %s at %.0f Hz, %s time, %s; wall z < 0 with K = 1000 N/m, B = 1 N*s/m: "
         "push the tool down into it (%.0f s, Ctrl-C ends)\n",
         info->name, rate, lockstep ? "lockstep" : "real",
         info->simulated ? "the simulated hand left still" : "no simulated hand", seconds);
  printf("%7s  %10s  %8s  %9s  %s\n", "time_s", "target_mm", "z_mm", "force_N", "contact");
  state.size = sizeof(state);
  if (lockstep) {
    const uint32_t per_step = rate / 100.0 >= 1.0 ? (uint32_t)(rate / 100.0) : 1u;
    int have_first = 0;
    uint64_t first_tick = 0, next_row_tick = 0, tick = 0;
    double t = 0.0;
    while (interrupted == 0 && t < seconds) {
      if (haptic_client_step(client, per_step, &tick, err) != HAPTIC_OK) return -1;
      if (!have_first) {
        have_first = 1;
        first_tick = tick;
        next_row_tick = tick;
      }
      t = (double)(tick - first_tick + per_step) / rate;
      if (tick >= next_row_tick && haptic_client_wait_for_tick(client, tick, &state, 2000, err) == HAPTIC_OK) {
        print_hand_row(t, &state);
        if (state.position.z * 1e3 < deepest_mm) deepest_mm = state.position.z * 1e3;
        if (state.force.z > strongest_n) strongest_n = state.force.z;
        next_row_tick = tick + ticks_per_row;
      }
    }
  } else {
    row_clock clock = {0, 0.0, 0.0, 0.0};
    const double end = now_s() + seconds;
    while (interrupted == 0 && now_s() < end) {
      if (haptic_client_connection_state(client) == HAPTIC_CONNECTION_ENDED) {
        /* An ADMIN's kick or an expired token: the client does not reconnect after that. */
        fprintf(stderr, "touch_wall: the server ended this session\n");
        return -2;
      }
      const int polled = haptic_client_poll_state(client, &state, 100, err);
      if (polled == HAPTIC_TIMEOUT) continue;
      if (polled != HAPTIC_OK) return -1;
      print_hand_row(row_clock_at(&clock, state.server_time), &state);
      if (state.position.z * 1e3 < deepest_mm) deepest_mm = state.position.z * 1e3;
      if (state.force.z > strongest_n) strongest_n = state.force.z;
    }
  }
  counters.size = sizeof(counters);
  if (haptic_client_receive_counters(client, &counters, err) != HAPTIC_OK) return -1;
  printf("touch_wall: done; deepest %.3f mm into the wall, largest push back %.3f N, %llu "
         "datagrams received\n", -deepest_mm, strongest_n, (unsigned long long)counters.accepted);
  return 0;
}

/* The simulated hand moves down into the wall and holds. */
static int press(haptic_client* client, const haptic_device_info* info, int lockstep,
                 haptic_error* err) {
  const double rate = info->loop_rate_hz;
  const uint32_t ticks_per_row = (uint32_t)(rate / 20.0);
  const double duration = DESCENT + HOLD;
  haptic_spring_field_spec spring;
  haptic_field* spring_field = NULL;
  haptic_state state;
  haptic_vec3 target = {0.0, 0.0, 0.0};
  haptic_receive_counters counters;
  uint64_t last_tick = 0;
  int status = 0;

  haptic_spring_field_spec_init(&spring);
  spring.anchor.z = START_Z;
  spring.stiffness = 20.0;
  spring.max_force = 2.0;
  if (haptic_client_add_spring_field(client, &spring, &spring_field, err) != HAPTIC_OK) return -1;

  printf("touch_wall: %s at %.0f Hz, %s time; wall z < 0 with K = 1000 N/m, B = 1 N*s/m\n",
         info->name, rate, lockstep ? "lockstep" : "real");
  printf("%7s  %10s  %8s  %9s  %s\n", "time_s", "target_mm", "z_mm", "force_N", "contact");
  state.size = sizeof(state);
  if (lockstep) {
    /* 10 ms steps, moving the hand's target between them; rows timed from the first step. */
    const uint32_t per_step = rate / 100.0 >= 1.0 ? (uint32_t)(rate / 100.0) : 1u;
    int have_first = 0;
    uint64_t first_tick = 0, next_row_tick = 0, tick = 0;
    double t = 0.0;
    while (t < duration) {
      target.z = target_at(t);
      if (haptic_client_set_operator_follow(client, target, HAND_STIFFNESS, HAND_DAMPING, err) != HAPTIC_OK ||
          haptic_client_step(client, per_step, &tick, err) != HAPTIC_OK) {
        status = -1;
        break;
      }
      last_tick = tick;
      if (!have_first) {
        have_first = 1;
        first_tick = tick;
        next_row_tick = tick;
      }
      t = (double)(tick - first_tick + per_step) / rate;
      /* The step's reply carries the tick's state, so this returns at once. */
      if (tick >= next_row_tick && haptic_client_wait_for_tick(client, tick, &state, 2000, err) == HAPTIC_OK) {
        print_row(t, target.z, &state);
        next_row_tick = tick + ticks_per_row;
      }
    }
  } else {
    const double start = now_s();
    double next_update = start, t = 0.0;
    row_clock clock = {0, 0.0, 0.0, 0.0};
    while (t < duration) {
      t = now_s() - start;
      target.z = target_at(t);
      if (haptic_client_set_operator_follow(client, target, HAND_STIFFNESS, HAND_DAMPING, err) != HAPTIC_OK) {
        status = -1;
        break;
      }
      if (haptic_client_poll_state(client, &state, 0, err) == HAPTIC_OK) {
        print_row(row_clock_at(&clock, state.server_time), target_at(t), &state);
      }
      next_update += 0.010;
      sleep_until_s(next_update);
    }
  }
  if (status == 0) {
    haptic_operator_input release;
    haptic_operator_input_init(&release);
    if (haptic_client_set_operator(client, &release, err) != HAPTIC_OK) status = -1;
  }
  if (status == 0 && lockstep) {
    /* Only what lockstep makes exact: the datagrams received depend on the network's timing. */
    printf("touch_wall: done; server at tick %llu\n", (unsigned long long)last_tick);
  } else if (status == 0) {
    haptic_stats stats;
    haptic_error stats_err;
    counters.size = sizeof(counters);
    stats.size = sizeof(stats);
    if (haptic_client_receive_counters(client, &counters, err) != HAPTIC_OK) {
      status = -1;
    } else if (haptic_client_stats(client, &stats, NULL, 0, NULL, 0, &stats_err) == HAPTIC_OK) {
      printf("touch_wall: done; server loop %.1f Hz, lateness p99 %.0f us, %llu datagrams received\n",
             stats.achieved_rate_hz, stats.lateness_p99_us, (unsigned long long)counters.accepted);
    } else if (stats_err.code == HAPTIC_ERROR_PERMISSION_DENIED) {  /* the loop's figures are an ADMIN's */
      printf("touch_wall: done; %llu datagrams received\n", (unsigned long long)counters.accepted);
    } else {
      *err = stats_err;
      status = -1;
    }
  }
  haptic_field_release(spring_field);  /* it goes with the session */
  return status;
}

static char* read_first_line(const char* path) {
  static char line[1024];
  FILE* file = fopen(path, "r");
  if (file == NULL) return NULL;
  if (fgets(line, sizeof(line), file) == NULL) {
    fclose(file);
    return NULL;
  }
  fclose(file);
  line[strcspn(line, "\r\n")] = '\0';
  return line;
}

int main(int argc, char** argv) {
  const char* address = "127.0.0.1:50051";
  const char* token_file = NULL;
  int lockstep = 0, hand = 0, i, status;
  double seconds = 10.0;
  haptic_client_config config;
  haptic_client* client = NULL;
  haptic_device_info info;
  haptic_wall_spec wall;
  haptic_object* wall_object = NULL;
  haptic_error err;

  if (haptic_c_version() != HAPTIC_C_VERSION) {
    fprintf(stderr, "touch_wall: libhaptic_c is version %u, this program was built for %u\n",
            haptic_c_version(), HAPTIC_C_VERSION);
    return 1;
  }
  haptic_client_config_init(&config);
  for (i = 1; i < argc; ++i) {
    const char* arg = argv[i];
    const char* value = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(arg, "--lockstep") == 0) {
      lockstep = 1;
    } else if (strcmp(arg, "--hand") == 0) {
      hand = 1;
    } else if (strcmp(arg, "--seconds") == 0) {
      char* end = NULL;
      if (value == NULL) return usage_error("--seconds needs a number", "");
      seconds = strtod(value, &end);
      ++i;
      if (end == value || *end != '\0' || !(seconds > 0.0 && seconds <= 3600.0)) {
        fprintf(stderr, "touch_wall: --seconds: '%s' is not a time of 0 to 3600 s\nusage: " USAGE "\n", value);
        return 2;
      }
    } else if (strcmp(arg, "--token") == 0) {
      if (value == NULL) return usage_error("--token needs the token", "");
      config.token = argv[++i];
    } else if (strcmp(arg, "--token-file") == 0) {
      if (value == NULL) return usage_error("--token-file needs a file", "");
      token_file = argv[++i];
    } else if (strcmp(arg, "--ca") == 0) {
      if (value == NULL) return usage_error("--ca needs a PEM file", "");
      config.tls_ca_file = argv[++i];
    } else if (strcmp(arg, "--cert") == 0) {
      if (value == NULL) return usage_error("--cert needs a PEM file", "");
      config.tls_cert_file = argv[++i];
    } else if (strcmp(arg, "--key") == 0) {
      if (value == NULL) return usage_error("--key needs a PEM file", "");
      config.tls_key_file = argv[++i];
    } else if (strcmp(arg, "--server-name") == 0) {
      if (value == NULL) return usage_error("--server-name needs a name", "");
      config.tls_server_name = argv[++i];
    } else if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
      printf("usage: " USAGE "\n");
      return 0;
    } else if (strncmp(arg, "--", 2) == 0) {
      return usage_error("unknown option ", arg);
    } else {
      address = arg;
    }
  }
  if (token_file != NULL) {
    const char* token = read_first_line(token_file);
    if (token == NULL) {
      fprintf(stderr, "touch_wall: --token-file: cannot read '%s'\nusage: " USAGE "\n", token_file);
      return 2;
    }
    config.token = token;
  }
  if (config.tls_ca_file[0] == '\0' &&
      (config.tls_cert_file[0] != '\0' || config.tls_key_file[0] != '\0' || config.tls_server_name[0] != '\0')) {
    return usage_error("--cert, --key and --server-name need --ca (TLS)", "");
  }
  config.server_address = address;
  config.client_name = "touch_wall";
  if (haptic_client_open(&config, &client, &err) != HAPTIC_OK) return failed(&err);

  info.size = sizeof(info);
  haptic_wall_spec_init(&wall);
  wall.impedance.stiffness = 1000.0;
  wall.impedance.damping = 1.0;
  if (haptic_client_device_info(client, &info, &err) != HAPTIC_OK ||
      haptic_client_subscribe(client, (uint32_t)(info.loop_rate_hz / 20.0), &err) != HAPTIC_OK ||
      haptic_client_add_wall(client, &wall, &wall_object, &err) != HAPTIC_OK) {
    status = -1;
  } else if (hand || !info.simulated) {
    status = watch(client, &info, lockstep, seconds, &err);
  } else {
    status = press(client, &info, lockstep, &err);
  }
  haptic_object_release(wall_object);  /* it goes with the session */
  if (status == -2) { /* said already: the server ended the session */
    haptic_client_close(client, NULL);
    return 1;
  }
  if (status != 0) {
    status = failed(&err);
    haptic_client_close(client, NULL);
    return status;
  }
  haptic_client_close(client, NULL);
  return 0;
}
