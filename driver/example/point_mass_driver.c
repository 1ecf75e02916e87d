/* An out-of-tree hapticd driver: a simulated 3-axis point mass (mass m, viscous damping b per
 * axis) with a constant push of its own standing in for an operator, built against
 * <haptic/driver.h> alone. Its joints are the tool point's x, y, z in W (m), read with their rates;
 * the command is the force on the tool (N), held over the tick and integrated exactly:
 *   v(t) = F/b + (v0 − F/b) e^(−b t / m),  x(t) = x0 + (F/b) t + (v0 − F/b)(m/b)(1 − e^(−b t / m))
 * (b = 0: x0 + v0 t + F t² / 2m), F the command plus the push.
 *
 * params (all optional; any other key, or a value of the wrong kind, is refused naming it):
 * {"mass": 0.01 kg, "damping": 0.02 N·s/m, "initial": [x, y, z] m,
 *   "push": [fx, fy, fz] N, "max_force": 10 N, "button_period_s": 0 (0: no button; else button 0
 *   is pressed for every other period), "servo_rate_hz": 0 (nonzero: device-clocked at that rate),
 *   "turn_rate": 0 rad/s (nonzero: the tool reports an orientation turning about z at this rate)
 *   "fault": "none" | "nan" | "stale" | "hang" | "fail_start" | "fail_when_safe", "fault_after": 0 ticks,
 *   "reported_mass": [mx, my, mz] kg (ABI 2: the apparent mass it reports instead of its own, for
 *   tests of what hapticd makes of a driver's model)}
 * The faults are for hapticd's driver test kit: from tick fault_after on, "nan" reads NaN,
 * "stale" stops the sample sequence, "hang" blocks read() until stop(); "fail_when_safe" fails
 * every write after enter_safe_state (against driver.h, which says such a write is taken).
 * ABI 2: it reports its mass and damping as the port's apparent mass-damper (so hapticd's
 * stability report and passivity controller know the device), its angular velocity with the
 * turning orientation, says in hapticd's log when it starts, and lists itself for
 * `hapticd --list-devices`. Built against a version 1 header (HAPTIC_DRIVER_ABI_VERSION 1) it is
 * a version 1 driver without those: the tests build it so, as an older driver.
 *
 * Build: cc -shared -fPIC -I<hapticd>/driver/include point_mass_driver.c -lm -o point_mass_driver.so
 */
#include <haptic/driver.h>

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct {
  double mass, damping, max_force, button_period_s, servo_rate_hz, turn_rate;
  double p[3], v[3], push[3];
  double reported_mass[3];
  int reports_mass;  /* reported_mass was given */
  char fault[16];
  uint64_t fault_after;
  uint64_t ticks;     /* writes so far */
  uint64_t sequence;  /* samples taken */
  double time_s;
  int safe;           /* enter_safe_state was called: no force until the next start */
  pthread_mutex_t lock;
  pthread_cond_t released;
  int stopping;
#if HAPTIC_DRIVER_ABI_VERSION >= 2
  haptic_driver_log_fn log;  /* hapticd's log (set_log), or NULL */
  void* log_context;
#endif
} point_mass;

/* Says `message` in hapticd's log where the ABI has one. */
static void say(const point_mass* d, int level, const char* message) {
#if HAPTIC_DRIVER_ABI_VERSION >= 2
  if (d->log != NULL) d->log(d->log_context, level, message);
#else
  (void)d;
  (void)level;
  (void)message;
#endif
}

/* A minimal reader for the flat JSON object hapticd passes: finds "key": and parses a number, a
 * [a, b, c] triple or a "string" after it. Each returns 1 when found, 0 when absent, and -1 with
 * `error` naming the key and what was expected when the value is of another kind. */
static const char* find_key(const char* json, const char* key) {
  char quoted[64];
  snprintf(quoted, sizeof quoted, "\"%s\"", key);
  const char* at = strstr(json, quoted);
  if (at == NULL) return NULL;
  at = strchr(at + strlen(quoted), ':');
  return at == NULL ? NULL : at + 1;
}
static int wrong(char* error, const char* key, const char* expected) {
  snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "params.%s: expected %s", key, expected);
  return -1;
}
static int number(const char* json, const char* key, double* out, char* error) {
  const char* at = find_key(json, key);
  if (at == NULL) return 0;
  char* end = NULL;
  const double value = strtod(at, &end);
  if (end == at) return wrong(error, key, "a number");
  while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r') ++end;
  if (*end != ',' && *end != '}') return wrong(error, key, "a number");
  *out = value;
  return 1;
}
static int triple(const char* json, const char* key, double out[3], char* error) {
  const char* at = find_key(json, key);
  if (at == NULL) return 0;
  while (*at == ' ') ++at;
  if (*at != '[') return wrong(error, key, "[x, y, z] (three numbers)");
  ++at;
  for (int i = 0; i < 3; ++i) {
    char* end = NULL;
    out[i] = strtod(at, &end);
    if (end == at) return wrong(error, key, "[x, y, z] (three numbers)");
    at = end;
    while (*at == ' ' || *at == ',') ++at;
  }
  if (*at != ']') return wrong(error, key, "[x, y, z] (three numbers)");
  return 1;
}
static int text(const char* json, const char* key, char* out, size_t size, char* error) {
  const char* at = find_key(json, key);
  if (at == NULL) return 0;
  while (*at == ' ') ++at;
  if (*at != '"') return wrong(error, key, "a string");
  const char* end = strchr(at + 1, '"');
  if (end == NULL || (size_t)(end - at - 1) >= size) return wrong(error, key, "a short string");
  memcpy(out, at + 1, (size_t)(end - at - 1));
  out[end - at - 1] = '\0';
  return 1;
}

/* The keys this driver takes: any other in params is refused, naming it (a misspelt "damping"
 * must not leave the default in force unseen). */
static const char* const kKeys[] = {"mass", "damping", "initial", "push", "max_force", "button_period_s",
                                    "servo_rate_hz", "turn_rate", "fault", "fault_after", "reported_mass"};

/* Checks that every key of the flat object `json` is one of kKeys; -1 with `error` naming the first
 * that is not (or what is not an object). Values are skipped: numbers, strings, [ ... ]. */
static int only_known_keys(const char* json, char* error) {
  const char* at = json;
  while (*at == ' ' || *at == '\n' || *at == '\t' || *at == '\r') ++at;
  if (*at != '{') {
    snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "params: expected a JSON object");
    return -1;
  }
  ++at;
  for (;;) {
    while (*at == ' ' || *at == ',' || *at == '\n' || *at == '\t' || *at == '\r') ++at;
    if (*at == '}' || *at == '\0') return 0;
    if (*at != '"') {
      snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "params: expected a quoted key");
      return -1;
    }
    const char* end = strchr(at + 1, '"');
    if (end == NULL) {
      snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "params: unterminated key");
      return -1;
    }
    const size_t length = (size_t)(end - at - 1);
    int known = 0;
    for (size_t k = 0; k < sizeof kKeys / sizeof kKeys[0]; ++k) {
      known |= strlen(kKeys[k]) == length && strncmp(kKeys[k], at + 1, length) == 0;
    }
    if (!known) {
      snprintf(error, HAPTIC_DRIVER_ERROR_SIZE,
               "params.%.*s: not an option of this driver (it takes mass, damping, initial, push, "
               "max_force, button_period_s, servo_rate_hz, turn_rate, fault, fault_after, reported_mass)",
               (int)(length < 64 ? length : 64), at + 1);
      return -1;
    }
    at = end + 1;
    while (*at == ' ' || *at == ':') ++at;
    /* The value: a string, a bracketed list (nested brackets and strings inside), or a bare word. */
    int depth = 0;
    while (*at != '\0') {
      if (*at == '"') {
        const char* close = strchr(at + 1, '"');
        if (close == NULL) break;
        at = close + 1;
        if (depth == 0) break;
        continue;
      }
      if (*at == '[' || *at == '{') ++depth;
      if (*at == ']' || *at == '}') {
        if (depth == 0) break;  /* the object's own end */
        --depth;
        ++at;
        if (depth == 0) break;
        continue;
      }
      if (*at == ',' && depth == 0) break;
      ++at;
    }
  }
}

static void* create(const char* params, char* error) {
  point_mass* d = calloc(1, sizeof *d);
  if (d == NULL) {
    snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "out of memory");
    return NULL;
  }
  d->mass = 0.01;
  d->damping = 0.02;
  d->max_force = 10.0;
  strcpy(d->fault, "none");
  double fault_after = 0.0;
  if (only_known_keys(params, error) < 0 || number(params, "mass", &d->mass, error) < 0 ||
      number(params, "damping", &d->damping, error) < 0 ||
      number(params, "max_force", &d->max_force, error) < 0 ||
      number(params, "button_period_s", &d->button_period_s, error) < 0 ||
      number(params, "servo_rate_hz", &d->servo_rate_hz, error) < 0 ||
      number(params, "turn_rate", &d->turn_rate, error) < 0 ||
      number(params, "fault_after", &fault_after, error) < 0 || triple(params, "initial", d->p, error) < 0 ||
      triple(params, "push", d->push, error) < 0 ||
      text(params, "fault", d->fault, sizeof d->fault, error) < 0 ||
      (d->reports_mass = triple(params, "reported_mass", d->reported_mass, error)) < 0) {
    free(d);  /* `error` names the key */
    return NULL;
  }
  if (!(d->mass > 0.0) || !(d->damping >= 0.0) || !(d->max_force > 0.0)) {
    snprintf(error, HAPTIC_DRIVER_ERROR_SIZE,
             "params.mass must be > 0, damping >= 0 and max_force > 0; got %g, %g, %g", d->mass,
             d->damping, d->max_force);
    free(d);
    return NULL;
  }
  if (strcmp(d->fault, "none") != 0 && strcmp(d->fault, "nan") != 0 &&
      strcmp(d->fault, "stale") != 0 && strcmp(d->fault, "hang") != 0 &&
      strcmp(d->fault, "fail_start") != 0 && strcmp(d->fault, "fail_when_safe") != 0) {
    snprintf(error, HAPTIC_DRIVER_ERROR_SIZE,
             "params.fault: expected none, nan, stale, hang, fail_start or fail_when_safe, got \"%s\"", d->fault);
    free(d);
    return NULL;
  }
  d->fault_after = (uint64_t)fault_after;
  pthread_mutex_init(&d->lock, NULL);
  pthread_cond_init(&d->released, NULL);
  return d;
}

static void destroy(void* driver) {
  point_mass* d = driver;
  pthread_cond_destroy(&d->released);
  pthread_mutex_destroy(&d->lock);
  free(d);
}

static int describe(void* driver, haptic_driver_info* info) {
  const point_mass* d = driver;
  memset(info, 0, sizeof *info);
  snprintf(info->name, sizeof info->name, "point mass driver (example plugin, %g kg)", d->mass);
  info->joints = 3;
  info->dof = 3;
  info->buttons = d->button_period_s > 0.0 ? 1u : 0u;
  info->capabilities = HAPTIC_DRIVER_MEASURED_RATES;
  if (d->turn_rate != 0.0) info->capabilities |= HAPTIC_DRIVER_ORIENTATION;
  info->max_force = d->max_force;
  for (int i = 0; i < 3; ++i) {
    info->workspace_min[i] = -0.1;
    info->workspace_max[i] = 0.1;
  }
  info->servo_rate_hz = d->servo_rate_hz;
#if HAPTIC_DRIVER_ABI_VERSION >= 2
  for (int i = 0; i < 3; ++i) { /* the plant itself, exactly: it is what the loop pushes */
    info->apparent_mass[i] = d->reports_mass ? d->reported_mass[i] : d->mass;
    info->apparent_damping[i] = d->damping;
  }
#endif
  return HAPTIC_DRIVER_OK;
}

#if HAPTIC_DRIVER_ABI_VERSION >= 2
/* Why a read or write failed: the injected fault (a real driver keeps its vendor's error). */
static void last_error(void* driver, char* error) {
  const point_mass* d = driver;
  const uint64_t ticks = __atomic_load_n(&d->ticks, __ATOMIC_RELAXED); /* the loop writes it */
  const int faulting_now = strcmp(d->fault, "none") != 0 && ticks >= d->fault_after;
  snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", faulting_now ? d->fault : "");
  if (faulting_now && strcmp(d->fault, "nan") == 0) {
    snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "the example's injected fault: a NaN reading");
  }
}

static void set_log(void* driver, haptic_driver_log_fn log, void* context) {
  point_mass* d = driver;
  d->log = log;
  d->log_context = context;
}

static int list_devices(const char* params, char* list, size_t size) {
  (void)params;  /* a simulation: always exactly one, whatever the params */
  snprintf(list, size, "{}\tpoint mass driver (example plugin, simulated)\n");
  return 1;
}
#endif

static int start(void* driver) {
  point_mass* d = driver;
  d->safe = 0;
  pthread_mutex_lock(&d->lock);
  d->stopping = 0;
  pthread_mutex_unlock(&d->lock);
  if (strcmp(d->fault, "fail_start") == 0) {
    say(d, 2, "start refused (fault \"fail_start\")");
    return HAPTIC_DRIVER_FAILED;
  }
  char message[128];
  snprintf(message, sizeof message, "started: %g kg, %g N*s/m per axis", d->mass, d->damping);
  say(d, 0, message);  /* 0, 2: HAPTIC_DRIVER_LOG_INFO, _ERROR of ABI 2 */
  return HAPTIC_DRIVER_OK;
}

static void stop(void* driver) {
  point_mass* d = driver;
  pthread_mutex_lock(&d->lock);
  d->stopping = 1;
  pthread_cond_broadcast(&d->released);
  pthread_mutex_unlock(&d->lock);
}

static int faulting(const point_mass* d, const char* kind) {
  return strcmp(d->fault, kind) == 0 && d->ticks >= d->fault_after;
}

static int read_sensors(void* driver, haptic_driver_reading* reading) {
  point_mass* d = driver;
  if (faulting(d, "hang")) {  /* a vendor call that never returns, until stop() */
    pthread_mutex_lock(&d->lock);
    while (!d->stopping) pthread_cond_wait(&d->released, &d->lock);
    pthread_mutex_unlock(&d->lock);
    return HAPTIC_DRIVER_FAILED;
  }
  memset(reading, 0, sizeof *reading);
  for (int i = 0; i < 3; ++i) {
    reading->q[i] = d->p[i];
    reading->q_dot[i] = d->v[i];
  }
  if (faulting(d, "nan")) reading->q[2] = NAN;
  if (!faulting(d, "stale")) ++d->sequence;
  reading->sequence = d->sequence;
  if (d->button_period_s > 0.0 && ((uint64_t)floor(d->time_s / d->button_period_s)) % 2 == 1) {
    reading->buttons = 1u;
  }
  reading->safe_state = (uint32_t)d->safe;
  /* A handle turning about z: R_WT = (cos(a/2), 0, 0, sin(a/2)), a = turn_rate t. */
  reading->orientation_W[0] = cos(0.5 * d->turn_rate * d->time_s);
  reading->orientation_W[3] = sin(0.5 * d->turn_rate * d->time_s);
#if HAPTIC_DRIVER_ABI_VERSION >= 2
  reading->angular_velocity_W[2] = d->turn_rate;
#endif
  return HAPTIC_DRIVER_OK;
}

static int write_command(void* driver, const haptic_driver_command* command, double dt) {
  point_mass* d = driver;
  if (!(dt > 0.0)) return HAPTIC_DRIVER_FAILED;
  if (d->safe && strcmp(d->fault, "fail_when_safe") == 0) return HAPTIC_DRIVER_FAILED;
  int ok = 1;
  for (int i = 0; i < 3; ++i) ok = ok && isfinite(command->tau[i]);
  const double m = d->mass, b = d->damping;
  for (int i = 0; i < 3; ++i) {
    const double F = (ok && !d->safe ? command->tau[i] : 0.0) + d->push[i];
    if (b > 0.0) {
      const double v_inf = F / b, decay = exp(-b * dt / m);
      d->p[i] += v_inf * dt + (d->v[i] - v_inf) * (m / b) * (1.0 - decay);
      d->v[i] = v_inf + (d->v[i] - v_inf) * decay;
    } else {
      d->p[i] += d->v[i] * dt + 0.5 * F / m * dt * dt;
      d->v[i] += F / m * dt;
    }
  }
  d->time_s += dt;
  ++d->ticks;
  return ok ? HAPTIC_DRIVER_OK : HAPTIC_DRIVER_FAILED;
}

static void enter_safe_state(void* driver) { ((point_mass*)driver)->safe = 1; }

static int run_servo(void* driver, haptic_driver_tick_fn tick, void* context) {
  point_mass* d = driver;
  if (!(d->servo_rate_hz > 0.0)) return HAPTIC_DRIVER_FAILED;
  const long period_ns = (long)(1e9 / d->servo_rate_hz);
  struct timespec next;
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (;;) {
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1000000000L) {
      next.tv_nsec -= 1000000000L;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
    const int64_t now = (int64_t)next.tv_sec * 1000000000LL + next.tv_nsec;
    if (tick(context, now) != 0) return HAPTIC_DRIVER_OK;
  }
}

static const haptic_driver_api kApi = {
    HAPTIC_DRIVER_ABI_VERSION,
    sizeof(haptic_driver_info),
    sizeof(haptic_driver_reading),
    sizeof(haptic_driver_command),
    create,
    destroy,
    describe,
    start,
    stop,
    read_sensors,
    write_command,
    enter_safe_state,
    run_servo,
#if HAPTIC_DRIVER_ABI_VERSION >= 2
    set_log,
    list_devices,
    last_error,
#endif
};

const haptic_driver_api* haptic_driver_entry(void) { return &kApi; }
