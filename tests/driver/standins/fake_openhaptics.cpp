// A stand-in for 3D Systems' OpenHaptics HD runtime (libHD.so, SOURCES.md §2.1), backed by a
// simulated plant, so that hapticd's driver for the Touch, Touch X and Phantom Premium can be
// loaded and exercised in ctest without the vendor's software or a device.
//
// Declarations are the project's own, written from the facts in driver/vendors/SOURCES.md §2 (see
// fake_openhaptics.hpp for every constant and its source). Behaviour the sources do not pin down
// is the stand-in's choice and is said so where it is made; README.md lists them.
//
// Control (for tests): fake_hd_control("command ..."), fake_hd_calls(), fake_hd_clear_calls(),
// fake_hd_blocked(); environment: FAKE_HD_DEVICES, FAKE_HD_CLOCK, FAKE_HD_SCRIPT.
#include "fake_openhaptics.hpp"
#include "standin_call_log.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#define FAKE_HD_EXPORT extern "C" __attribute__((visibility("default")))

using namespace fake_hd;

namespace {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major, R(i,j) = m[3*i+j]
using Clock = std::chrono::steady_clock;

// ---- The plant's constants: the stand-in's own choices (no vendor figure exists for them) ----
constexpr double kGimbalInertia = 1e-4;  // kg·m² per gimbal joint (Premium 6DOF)
constexpr double kGimbalDamping = 1e-3;  // N·m·s/rad per gimbal joint
constexpr double kMaxBoxFactor = 1.2;    // HD_MAX_WORKSPACE_DIMENSIONS = 1.2 × the usable box
constexpr std::size_t kMaxErrors = 32;   // per-thread error stack depth; the oldest are dropped
constexpr std::size_t kMaxCallbacks = 256;  // more scheduled at once: HD_SCHEDULER_FULL
constexpr int kFirstSerial = 10001;            // "10001", "10002", ... in list order
constexpr HDint kButtons = HD_DEVICE_BUTTON_1 | HD_DEVICE_BUTTON_2;  // two buttons (§2.4 bits)
constexpr const char* kVersionString = "3.4.0";       // HD_VERSION: the 3.4 runtime (§2.1)
constexpr const char* kVendorString = "3D Systems";   // HD_DEVICE_VENDOR (stand-in's choice)
constexpr const char* kDriverVersionString = "stand-in";  // HD_DEVICE_DRIVER_VERSION

// ---- The models FAKE_HD_DEVICES may name ----
struct Model {
  const char* name;       // FAKE_HD_DEVICES spelling and HD_DEVICE_MODEL_TYPE
  double max_force;       // N, HD_NOMINAL_MAX_FORCE (continuous: half of it)
  double radius_mm;       // usable workspace: a box of ±radius per axis
  HDint output_dof;       // HD_OUTPUT_DOF (HD_INPUT_DOF is 6 on every model)
  HDint calibration;      // HD_CALIBRATION_STYLE
  double mass;            // kg (stand-in's choice)
  double damping;         // N·s/m per axis (stand-in's choice)
  bool active_gimbal;     // gimbal driven by HD_CURRENT_GIMBAL_TORQUE (6DOF)
};

// Model strings: §2.5 "Model strings that CHAI3D matches" ([CHAI-PH] 495-603); "Touch X" is not
// among them (§2.6: not found) and is spelled as the product is named. Max force and workspace
// radius: §2.6, CHAI3D's table. Touch X: not found (§2.6); 7.9 N is CHAI3D's figure for the
// "PHANTOM Desktop" it succeeds, and its workspace is taken as the Touch's (stand-in's choice).
// Calibration styles: §2.4 values; which model has which is the stand-in's choice (the Touch
// calibrates in its inkwell, the others by encoder reset).
constexpr Model kModels[] = {
    // §2.6, [CHAI-PH] lines 495-507: 3.3 N, 0.075 m
    {"Touch", 3.3, 75.0, 3, HD_CALIBRATION_INKWELL, 0.05, 0.5, false},
    // §2.6: not found; the Desktop's 7.9 N ([CHAI-PH] 543-555) and the Touch's workspace
    {"Touch X", 7.9, 75.0, 3, HD_CALIBRATION_ENCODER_RESET, 0.05, 0.5, false},
    // §2.6, [CHAI-PH] lines 567-579: 8.5 N, 0.12 m
    {"PHANTOM Premium 1.5 6DOF", 8.5, 120.0, 6, HD_CALIBRATION_ENCODER_RESET, 0.1, 1.0, true},
};

const Model* find_model(const std::string& name) {
  for (const Model& m : kModels)
    if (name == m.name) return &m;
  return nullptr;
}

// Fixed English texts (the stand-in's own wording), one per code of §2.4.
const char* error_text(HDerror code) {
  switch (code) {
    case HD_SUCCESS: return "no error";
    case HD_INVALID_ENUM: return "invalid enumeration value";
    case HD_INVALID_VALUE: return "invalid value";
    case HD_INVALID_OPERATION: return "invalid operation";
    case HD_INVALID_INPUT_TYPE: return "invalid input type for this parameter";
    case HD_BAD_HANDLE: return "invalid device handle";
    case HD_WARM_MOTORS: return "motors are warm";
    case HD_EXCEEDED_MAX_FORCE: return "exceeded the nominal maximum force";
    case HD_EXCEEDED_MAX_FORCE_IMPULSE: return "exceeded the maximum force impulse";
    case HD_EXCEEDED_MAX_VELOCITY: return "exceeded the maximum velocity";
    case HD_FORCE_ERROR: return "force error";
    case HD_DEVICE_FAULT: return "device fault";
    case HD_DEVICE_ALREADY_INITIATED: return "device already initialized";
    case HD_COMM_ERROR: return "communication error with the device";
    case HD_COMM_CONFIG_ERROR: return "communication configuration error";
    case HD_TIMER_ERROR: return "timer error";
    case HD_ILLEGAL_BEGIN: return "illegal begin of a haptic frame";
    case HD_ILLEGAL_END: return "illegal end of a haptic frame";
    case HD_FRAME_ERROR: return "haptic frame error";
    case HD_INVALID_PRIORITY: return "invalid scheduler priority";
    case HD_SCHEDULER_FULL: return "scheduler full";
    case HD_INVALID_LICENSE: return "invalid license";
    default: return "unknown error";
  }
}

// ---- Per-thread error stack (§2.3: hdGetError gives the most recent first, HD_SUCCESS when
// empty). A `reset` empties every thread's stack: each remembers the generation it belongs to. ----
struct ErrorStack {
  unsigned long generation = 0;
  std::vector<HDErrorInfo> errors;
};
thread_local ErrorStack t_errors;

// True on the thread that is running a scheduler tick (the servo thread, or the test's thread
// under the manual clock): callbacks scheduled from it run at once (§2.3).
thread_local bool t_in_tick = false;

// What a frame sees: the device's state when hdBeginFrame was called, in the API's units.
struct Snapshot {
  Vec3 p{};  // mm
  Vec3 v{};  // mm/s
  Vec3 g{};  // gimbal angles, rad
  Vec3 w{};  // angular velocity, rad/s
  Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
  HDint buttons = 0;
};

struct Device {
  std::string name;  // the configuration name hdInitDevice takes
  const Model* model = nullptr;
  const char* serial = "";
  bool plugged = true;
  bool initialized = false;
  HHD handle = HD_INVALID_HANDLE;
  bool calibrated = false;  // starts HD_CALIBRATION_NEEDS_UPDATE
  std::map<HDenum, bool> caps;
  // The plant, in SI units (m, m/s, N; rad, rad/s, N·m).
  Vec3 p{}, v{}, hand{};
  Vec3 g{}, gd{};   // gimbal joint angles and rates
  HDint buttons = 0;
  Vec3 f_out{}, t_out{};  // committed force (N) and gimbal torque (N·m), acting on the plant
  // Frames.
  bool in_frame = false;
  bool have_frame = false;  // a frame has been begun since init (so `cur` is meaningful)
  Snapshot cur, last;
  Vec3 f_frame{}, t_frame{};  // set during the open frame (N; mN·m)
  bool f_set = false, t_set = false;
  // `hang NAME [SECONDS]`
  bool hang_pending = false;
  double hang_seconds = 0;
};

struct Entry {
  HDSchedulerHandle handle;
  HDSchedulerCallback callback;
  void* data;
  HDushort priority;
  unsigned long seq;      // ties in priority run in the order scheduled
  bool sync;
  bool* done;             // sync: set when it has run
  bool running = false;
  bool removed = false;   // hdUnschedule'd while running
};

struct ScriptItem {
  long tick;
  std::string command;
};

struct State {
  std::mutex mu;
  std::condition_variable cv;        // hangs, completions, ticks, unschedules
  std::condition_variable servo_cv;  // the servo thread's sleep between ticks
  bool loaded = false;
  unsigned long generation = 1;      // bumped by `reset` (error stacks compare with it)
  unsigned long release_gen = 0;     // bumped by `release` and `reset`
  int blocked = 0;                   // hdBeginFrame calls blocked in a hang right now
  std::vector<Device> devices;
  HHD current = HD_INVALID_HANDLE;   // the current device, process-wide
  HHD next_handle = 0;
  bool manual_clock = false;         // FAKE_HD_CLOCK=manual
  // Scheduler.
  bool started = false;              // hdStartScheduler in effect
  bool stop = false;                 // the servo thread must leave
  std::thread servo;
  bool servo_alive = false;
  HDulong rate = kDefaultSchedulerRate;
  long ticks = 0;                    // ticks run since the last reset
  bool ticking = false;              // a tick is in progress (on some thread)
  Clock::time_point tick_start = Clock::now();
  std::vector<Entry> entries;
  HDSchedulerHandle next_sched = 1;  // 0 is never a valid scheduler handle
  unsigned long next_seq = 0;
  // Script.
  std::vector<ScriptItem> script;
  std::size_t script_next = 0;
  bool in_script = false;
  // Log.
  standin::CallLog log;
  // Interned serial-number strings (stable for the process: hdGetString's pointers stay valid).
  std::map<int, std::string> serials;
};

// Never destroyed: a call may still be blocked in a hang when the process exits. The library is
// linked with -z nodelete, so the pointer stays reachable.
State& state() {
  static State* s = new State;
  return *s;
}

// ---- Errors ----

void push_error(State& s, HDerror code, HHD h) {
  if (t_errors.generation != s.generation) {
    t_errors.generation = s.generation;
    t_errors.errors.clear();
  }
  if (t_errors.errors.size() >= kMaxErrors) t_errors.errors.erase(t_errors.errors.begin());
  t_errors.errors.push_back(HDErrorInfo{code, 0, h});
}

// ---- Call log ----

std::string hex(HDenum e) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04x", e);
  return buf;
}

void log_line(State& s, std::string line, bool countable) {
  s.log.add(std::move(line), countable);
}

// ---- Text helpers ----

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

bool parse_double(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && std::isfinite(out);
}

// ---- Loading the configuration ----

int control_locked(State& s, const std::string& command);

void run_script(State& s) {
  s.in_script = true;
  while (s.script_next < s.script.size() && s.script[s.script_next].tick <= s.ticks) {
    const std::string command = s.script[s.script_next++].command;
    if (control_locked(s, command) != 0)
      std::fprintf(stderr, "fake libHD: FAKE_HD_SCRIPT: '%s' failed at tick %ld\n",
                   command.c_str(), s.ticks);
  }
  s.in_script = false;
}

const char* serial_string(State& s, int serial) {
  auto it = s.serials.find(serial);
  if (it == s.serials.end()) it = s.serials.emplace(serial, std::to_string(serial)).first;
  return it->second.c_str();
}

void load_locked(State& s) {
  s.devices.clear();
  s.current = HD_INVALID_HANDLE;
  s.next_handle = 0;
  s.started = false;
  s.stop = false;
  s.rate = kDefaultSchedulerRate;
  s.ticks = 0;
  s.ticking = false;
  s.entries.clear();
  s.next_sched = 1;
  s.next_seq = 0;
  s.script.clear();
  s.script_next = 0;
  s.log.clear();
  s.log.throw_from("");

  const char* env = std::getenv("FAKE_HD_DEVICES");
  const std::string list = env ? env : "Default Device=Touch";
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    item = trim(item);
    if (item.empty()) continue;
    const auto eq = item.find('=');
    const std::string name = eq == std::string::npos ? std::string() : trim(item.substr(0, eq));
    const std::string model_name = eq == std::string::npos ? item : trim(item.substr(eq + 1));
    const Model* model = find_model(model_name);
    bool duplicate = false;
    for (const Device& d : s.devices) duplicate |= d.name == name;
    if (name.empty() || !model || duplicate) {
      std::fprintf(stderr,
                   "fake libHD: FAKE_HD_DEVICES: '%s' left out (want NAME=MODEL, a new NAME, and "
                   "MODEL one of Touch, Touch X, PHANTOM Premium 1.5 6DOF)\n",
                   item.c_str());
      continue;
    }
    Device d;
    d.name = name;
    d.model = model;
    d.serial = serial_string(s, kFirstSerial + static_cast<int>(s.devices.size()));
    s.devices.push_back(std::move(d));
  }

  const char* clock = std::getenv("FAKE_HD_CLOCK");
  s.manual_clock = clock && std::string(clock) == "manual";
  if (clock && !s.manual_clock && *clock && std::string(clock) != "thread")
    std::fprintf(stderr, "fake libHD: FAKE_HD_CLOCK: '%s' is neither 'manual' nor 'thread'; "
                         "using the servo thread\n", clock);

  const char* script = std::getenv("FAKE_HD_SCRIPT");
  if (script) {
    std::stringstream sin(script);
    while (std::getline(sin, item, ';')) {
      item = trim(item);
      if (item.empty()) continue;
      char* end = nullptr;
      const long tick = std::strtol(item.c_str(), &end, 10);
      const std::string command = trim(end ? std::string(end) : std::string());
      if (end == item.c_str() || tick < 0 || command.empty()) {
        std::fprintf(stderr, "fake libHD: FAKE_HD_SCRIPT: bad item '%s' left out\n",
                     item.c_str());
        continue;
      }
      auto at = s.script.begin();  // kept in order of tick (stable for equal ticks)
      while (at != s.script.end() && at->tick <= tick) ++at;
      s.script.insert(at, ScriptItem{tick, command});
    }
  }
  s.loaded = true;
}

State& loaded_state(std::unique_lock<std::mutex>& lock) {
  State& s = state();
  lock = std::unique_lock<std::mutex>(s.mu);
  if (!s.loaded) {
    load_locked(s);
    run_script(s);  // the items due at tick 0
  }
  return s;
}

// ---- Devices ----

Device* by_handle(State& s, HHD h) {
  if (h == HD_INVALID_HANDLE) return nullptr;
  for (Device& d : s.devices)
    if (d.initialized && d.handle == h) return &d;
  return nullptr;
}

Device* by_name(State& s, const std::string& name) {
  for (Device& d : s.devices)
    if (d.name == name) return &d;
  return nullptr;
}

// The current device, or nullptr with HD_BAD_HANDLE pushed. An unplugged one pushes HD_COMM_ERROR
// and gives nullptr unless `allow_unplugged`.
Device* current_device(State& s, bool allow_unplugged = false) {
  Device* d = by_handle(s, s.current);
  if (!d) {
    push_error(s, HD_BAD_HANDLE, s.current);
    return nullptr;
  }
  if (!d->plugged && !allow_unplugged) {
    push_error(s, HD_COMM_ERROR, d->handle);
    return nullptr;
  }
  return d;
}

void reset_capabilities(Device& d) {
  // HD_FORCE_OUTPUT starts off (the stand-in's choice: a driver must hdEnable it, as the canonical
  // sequence of §2.3 does); HD_MAX_FORCE_CLAMPING starts on (taken to be the real runtime's
  // default; SOURCES.md does not say). The others are recorded and have no effect.
  d.caps = {{HD_FORCE_OUTPUT, false},          {HD_MAX_FORCE_CLAMPING, true},
            {HD_FORCE_RAMPING, false},         {HD_SOFTWARE_FORCE_LIMIT, false},
            {HD_ONE_FRAME_LIMIT, false},       {HD_SOFTWARE_VELOCITY_LIMIT, false},
            {HD_SOFTWARE_FORCE_IMPULSE_LIMIT, false}};
}

// ---- Plant ----

// One step of m·dv/dt = F − b·v over dt, exact for a constant F.
void integrate(double m, double b, double F, double dt, double& x, double& v) {
  const double a = b / m;
  const double e = std::exp(-a * dt);
  const double v_inf = F / b;
  x += v_inf * dt + (v - v_inf) * (1.0 - e) / a;
  v = v_inf + (v - v_inf) * e;
}

Mat3 mul(const Mat3& A, const Mat3& B) {
  Mat3 C{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) C[3 * i + j] += A[3 * i + k] * B[3 * k + j];
  return C;
}

Mat3 rot_x(double a) { return {1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a)}; }
Mat3 rot_y(double a) { return {std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a)}; }
Mat3 rot_z(double a) { return {std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1}; }

// The gimbal (the stand-in's own kinematics; no source gives the real one): joint 0 turns about
// the device's y (up), joint 1 about the x it carries, joint 2 about the stylus axis z (toward the
// user at rest), so R = Ry(g0)·Rx(g1)·Rz(g2), and the arm adds no rotation.
Mat3 gimbal_rotation(const Vec3& g) { return mul(mul(rot_y(g[0]), rot_x(g[1])), rot_z(g[2])); }

Vec3 gimbal_angles(const Mat3& R) {
  const double s1 = std::clamp(-R[5], -1.0, 1.0);  // -R(1,2) = sin g1
  return {std::atan2(R[2], R[8]), std::asin(s1), std::atan2(R[3], R[4])};
}

// Angular velocity in the device frame: ġ0·y + ġ1·Ry(g0)x + ġ2·Ry(g0)Rx(g1)z.
Vec3 angular_velocity(const Vec3& g, const Vec3& gd) {
  const Mat3 A = rot_y(g[0]);
  const Mat3 B = mul(A, rot_x(g[1]));
  Vec3 w{};
  for (int i = 0; i < 3; ++i) w[i] = gd[0] * (i == 1 ? 1.0 : 0.0) + gd[1] * A[3 * i + 0] +
                                     gd[2] * B[3 * i + 2];
  return w;
}

// Rotation matrix of the rotation vector r (Rodrigues).
Mat3 rotation(const Vec3& r) {
  const double angle = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (angle < 1e-15) return {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double x = r[0] / angle, y = r[1] / angle, z = r[2] / angle;
  const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
          t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
          t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}

Snapshot snapshot(const Device& d) {
  Snapshot f;
  for (int i = 0; i < 3; ++i) {
    f.p[i] = d.p[i] * 1000.0;  // m → mm (§2.5)
    f.v[i] = d.v[i] * 1000.0;  // m/s → mm/s
  }
  f.g = d.g;
  f.R = gimbal_rotation(d.g);
  f.w = angular_velocity(d.g, d.gd);
  f.buttons = d.buttons;
  return f;
}

void step(Device& d, double dt) {
  const Model& m = *d.model;
  const double half = kMaxBoxFactor * m.radius_mm / 1000.0;  // m
  for (int i = 0; i < 3; ++i) {
    integrate(m.mass, m.damping, d.f_out[i] + d.hand[i], dt, d.p[i], d.v[i]);
    if (d.p[i] > half) d.p[i] = half, d.v[i] = 0;
    if (d.p[i] < -half) d.p[i] = -half, d.v[i] = 0;
  }
  if (m.active_gimbal)
    for (int j = 0; j < 3; ++j)
      integrate(kGimbalInertia, kGimbalDamping, d.t_out[j], dt, d.g[j], d.gd[j]);
}

void cut_forces(Device& d) {
  d.f_out = {};
  d.t_out = {};
}

// ---- The scheduler ----

Entry* find_entry(State& s, HDSchedulerHandle h) {
  for (Entry& e : s.entries)
    if (e.handle == h) return &e;
  return nullptr;
}

void erase_entry(State& s, HDSchedulerHandle h) {
  s.entries.erase(std::remove_if(s.entries.begin(), s.entries.end(),
                                 [h](const Entry& e) { return e.handle == h; }),
                  s.entries.end());
}

// One servo tick on the calling thread, with the lock held on entry and on return (it is released
// while each callback runs). Runs the script items due, every scheduled callback once in
// decreasing priority (ties in the order scheduled), then advances every plant by one period.
void run_tick(State& s, std::unique_lock<std::mutex>& lock) {
  const unsigned long generation = s.generation;
  s.ticking = true;
  t_in_tick = true;
  s.tick_start = Clock::now();
  run_script(s);
  std::vector<Entry> order = s.entries;
  std::stable_sort(order.begin(), order.end(), [](const Entry& a, const Entry& b) {
    return a.priority != b.priority ? a.priority > b.priority : a.seq < b.seq;
  });
  for (const Entry& planned : order) {
    Entry* e = find_entry(s, planned.handle);
    if (!e || e->removed) continue;
    e->running = true;
    const HDSchedulerCallback callback = e->callback;
    void* const data = e->data;
    lock.unlock();
    const HDCallbackCode code = callback(data);
    lock.lock();
    if (s.generation != generation) {  // `reset` meanwhile: this tick is void
      t_in_tick = false;
      return;
    }
    e = find_entry(s, planned.handle);
    if (!e) continue;
    e->running = false;
    if (e->sync) {
      *e->done = true;  // a synchronous callback runs once, whatever it returns
      erase_entry(s, planned.handle);
    } else if (e->removed || code != HD_CALLBACK_CONTINUE) {
      erase_entry(s, planned.handle);  // HD_CALLBACK_DONE (or anything else) ends it
    }
    s.cv.notify_all();
  }
  const double dt = 1.0 / static_cast<double>(s.rate);
  for (Device& d : s.devices) step(d, dt);
  ++s.ticks;
  s.ticking = false;
  t_in_tick = false;
  s.cv.notify_all();
}

void servo_main(unsigned long generation) {
  State& s = state();
  std::unique_lock<std::mutex> lock(s.mu);
  auto next = Clock::now();
  while (!s.stop && s.generation == generation) {
    run_tick(s, lock);
    if (s.generation != generation) break;
    next += std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / static_cast<double>(s.rate)));
    const auto now = Clock::now();
    if (now - next > std::chrono::milliseconds(50)) next = now;  // far behind: start afresh
    s.servo_cv.wait_until(lock, next, [&] { return s.stop || s.generation != generation; });
  }
  s.servo_alive = false;
  s.cv.notify_all();
}

// Stops the servo thread: the caller holds the lock; it is released while waiting. Waits for the
// thread to leave (at most 2 s if `bounded`), then joins it, or detaches it if it is stuck in a
// callback past the bound.
void stop_servo_thread(State& s, std::unique_lock<std::mutex>& lock, bool bounded) {
  s.stop = true;
  s.servo_cv.notify_all();
  if (!s.servo.joinable()) return;
  if (s.servo.get_id() == std::this_thread::get_id()) return;  // it leaves after this tick
  auto left_loop = [&] { return !s.servo_alive; };
  bool left = true;
  if (bounded)
    left = s.cv.wait_for(lock, std::chrono::seconds(2), left_loop);
  else
    s.cv.wait(lock, left_loop);
  std::thread servo = std::move(s.servo);
  lock.unlock();
  if (left)
    servo.join();
  else
    servo.detach();
  lock.lock();
}

// Waits until no tick is in progress on another thread.
void wait_not_ticking(State& s, std::unique_lock<std::mutex>& lock) {
  s.cv.wait(lock, [&] { return !s.ticking; });
}

// At exit (registered when the scheduler first starts) and at unload: the servo thread must not
// run callbacks into a program that is shutting down.
void shutdown_scheduler() {
  State& s = state();
  std::unique_lock<std::mutex> lock(s.mu);
  s.started = false;
  for (Device& d : s.devices) d.hang_pending = false;
  ++s.release_gen;
  s.cv.notify_all();
  stop_servo_thread(s, lock, /*bounded=*/true);
}

__attribute__((destructor)) void at_unload() { shutdown_scheduler(); }

// ---- Control commands ----

struct Words {
  std::vector<std::string> words;
  std::vector<std::size_t> begin, end;  // offsets in the command
};

Words split(const std::string& text) {
  Words w;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i >= text.size()) break;
    const std::size_t b = i;
    while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    w.words.push_back(text.substr(b, i - b));
    w.begin.push_back(b);
    w.end.push_back(i);
  }
  return w;
}

// The device named by words 1..n-1-trailing (names may hold spaces: "Default Device").
Device* named(State& s, const std::string& command, const Words& w, std::size_t trailing) {
  if (w.words.size() < 2 + trailing) return nullptr;
  const std::size_t last = w.words.size() - 1 - trailing;
  return by_name(s, command.substr(w.begin[1], w.end[last] - w.begin[1]));
}

bool numbers(const Words& w, std::size_t count, double* out) {
  for (std::size_t i = 0; i < count; ++i)
    if (!parse_double(w.words[w.words.size() - count + i], out[i])) return false;
  return true;
}

int control_locked(State& s, const std::string& command) {
  const Words w = split(command);
  if (w.words.empty()) return -1;
  const std::string& verb = w.words[0];
  if (verb == "throw") {  // `throw FUNCTION`: its calls throw from now on; `throw none` ends it
    if (w.words.size() != 2) return -1;
    s.log.throw_from(w.words[1] == "none" ? "" : w.words[1]);
    return 0;
  }
  if (verb == "release") {
    if (w.words.size() != 1) return -1;
    for (Device& d : s.devices) d.hang_pending = false;
    ++s.release_gen;
    s.cv.notify_all();
    return 0;
  }
  if (verb == "unplug" || verb == "replug" || verb == "uncalibrate") {
    Device* d = named(s, command, w, 0);
    if (!d) return -1;
    if (verb == "unplug") {
      d->plugged = false;
      cut_forces(*d);
      if (d->initialized) d->caps[HD_FORCE_OUTPUT] = false;  // off until hdEnable again
    } else if (verb == "replug") {
      d->plugged = true;
    } else {
      d->calibrated = false;
    }
    return 0;
  }
  if (verb == "hang") {
    Device* d = named(s, command, w, 0);
    double seconds = 0;  // 0: until `release`
    if (!d) {
      d = named(s, command, w, 1);
      if (!d || !numbers(w, 1, &seconds) || seconds < 0) return -1;
    }
    d->hang_pending = true;
    d->hang_seconds = seconds;
    return 0;
  }
  if (verb == "hand" || verb == "turn") {
    Device* d = named(s, command, w, 3);
    Vec3 x{};
    if (!d || !numbers(w, 3, x.data())) return -1;
    if (verb == "hand") {
      d->hand = x;  // N, device frame
    } else {
      d->g = gimbal_angles(rotation(x));
      d->gd = {};
    }
    return 0;
  }
  if (verb == "button") {
    Device* d = named(s, command, w, 1);
    if (!d) return -1;
    char* end = nullptr;
    const std::string& text = w.words.back();
    const unsigned long mask = std::strtoul(text.c_str(), &end, 0);
    if (end == text.c_str() || *end != '\0') return -1;
    d->buttons = static_cast<HDint>(mask & static_cast<unsigned long>(kButtons));
    return 0;
  }
  return -1;  // `reset` and `tick` are handled by fake_hd_control itself, never in a script
}

// ---- Parameters ----

enum class Kind { Unknown, Real, Integer, String };

Kind kind_of(HDenum pname) {
  switch (pname) {
    case HD_CURRENT_BUTTONS:
    case HD_LAST_BUTTONS:
    case HD_INPUT_DOF:
    case HD_OUTPUT_DOF:
    case HD_CALIBRATION_STYLE:
    case HD_UPDATE_RATE:
    case HD_INSTANTANEOUS_UPDATE_RATE:
      return Kind::Integer;
    case HD_CURRENT_POSITION:
    case HD_CURRENT_VELOCITY:
    case HD_CURRENT_TRANSFORM:
    case HD_CURRENT_ANGULAR_VELOCITY:
    case HD_CURRENT_GIMBAL_ANGLES:
    case HD_LAST_POSITION:
    case HD_LAST_VELOCITY:
    case HD_LAST_TRANSFORM:
    case HD_LAST_ANGULAR_VELOCITY:
    case HD_LAST_GIMBAL_ANGLES:
    case HD_MAX_WORKSPACE_DIMENSIONS:
    case HD_USABLE_WORKSPACE_DIMENSIONS:
    case HD_NOMINAL_MAX_FORCE:
    case HD_NOMINAL_MAX_CONTINUOUS_FORCE:
    case HD_CURRENT_FORCE:
    case HD_CURRENT_TORQUE:
    case HD_CURRENT_GIMBAL_TORQUE:
    case HD_LAST_FORCE:
    case HD_LAST_TORQUE:
    case HD_LAST_GIMBAL_TORQUE:
      return Kind::Real;
    case HD_VERSION:
    case HD_DEVICE_MODEL_TYPE:
    case HD_DEVICE_DRIVER_VERSION:
    case HD_DEVICE_VENDOR:
    case HD_DEVICE_SERIAL_NUMBER:
      return Kind::String;
    default:
      return Kind::Unknown;
  }
}

// How many values hdSet*v reads for a settable parameter (0: not settable here).
int set_count(HDenum pname) {
  switch (pname) {
    case HD_CURRENT_FORCE:
    case HD_CURRENT_TORQUE:
    case HD_CURRENT_GIMBAL_TORQUE:
      return 3;
    default:
      return 0;
  }
}

void transform(const Snapshot& f, std::vector<double>& out) {
  // Column-major 4×4 with the translation in mm at 12..14 (§2.5, [OH-REF] p.A-2; [CHAI-HDP]
  // 907-916 reads frame[12..14]).
  out.assign(16, 0.0);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[4 * c + r] = f.R[3 * r + c];
  for (int r = 0; r < 3; ++r) out[12 + r] = f.p[r];
  out[15] = 1.0;
}

void vec(const Vec3& v, double scale, std::vector<double>& out) {
  out = {v[0] * scale, v[1] * scale, v[2] * scale};
}

// The values of a numeric parameter of device d (kind Real or Integer).
void values(const State& s, const Device& d, HDenum pname, std::vector<double>& out) {
  const Model& m = *d.model;
  const Snapshot live = d.in_frame ? d.cur : snapshot(d);
  const Snapshot& last = d.have_frame ? d.last : live;
  const double r = m.radius_mm, big = kMaxBoxFactor * m.radius_mm;
  switch (pname) {
    case HD_CURRENT_BUTTONS: out = {double(live.buttons)}; break;
    case HD_LAST_BUTTONS: out = {double(last.buttons)}; break;
    case HD_INPUT_DOF: out = {6.0}; break;
    case HD_OUTPUT_DOF: out = {double(m.output_dof)}; break;
    case HD_CALIBRATION_STYLE: out = {double(m.calibration)}; break;
    case HD_UPDATE_RATE:
    case HD_INSTANTANEOUS_UPDATE_RATE: out = {double(s.rate)}; break;
    case HD_CURRENT_POSITION: vec(live.p, 1, out); break;
    case HD_CURRENT_VELOCITY: vec(live.v, 1, out); break;
    case HD_CURRENT_TRANSFORM: transform(live, out); break;
    case HD_CURRENT_ANGULAR_VELOCITY: vec(live.w, 1, out); break;
    case HD_CURRENT_GIMBAL_ANGLES: vec(live.g, 1, out); break;
    case HD_LAST_POSITION: vec(last.p, 1, out); break;
    case HD_LAST_VELOCITY: vec(last.v, 1, out); break;
    case HD_LAST_TRANSFORM: transform(last, out); break;
    case HD_LAST_ANGULAR_VELOCITY: vec(last.w, 1, out); break;
    case HD_LAST_GIMBAL_ANGLES: vec(last.g, 1, out); break;
    case HD_MAX_WORKSPACE_DIMENSIONS: out = {-big, -big, -big, big, big, big}; break;
    case HD_USABLE_WORKSPACE_DIMENSIONS: out = {-r, -r, -r, r, r, r}; break;
    case HD_NOMINAL_MAX_FORCE: out = {m.max_force}; break;
    case HD_NOMINAL_MAX_CONTINUOUS_FORCE: out = {m.max_force / 2.0}; break;
    case HD_CURRENT_FORCE: vec(d.in_frame && d.f_set ? d.f_frame : d.f_out, 1, out); break;
    case HD_LAST_FORCE: vec(d.f_out, 1, out); break;
    case HD_CURRENT_TORQUE:
    case HD_CURRENT_GIMBAL_TORQUE:  // mN·m (§2.5)
      if (d.in_frame && d.t_set)
        vec(d.t_frame, 1, out);
      else
        vec(d.t_out, 1000.0, out);
      break;
    case HD_LAST_TORQUE:
    case HD_LAST_GIMBAL_TORQUE: vec(d.t_out, 1000.0, out); break;
    default: out.clear();
  }
}

const char* string_of(const Device& d, HDenum pname) {
  switch (pname) {
    case HD_VERSION: return kVersionString;
    case HD_DEVICE_MODEL_TYPE: return d.model->name;
    case HD_DEVICE_DRIVER_VERSION: return kDriverVersionString;
    case HD_DEVICE_VENDOR: return kVendorString;
    case HD_DEVICE_SERIAL_NUMBER: return d.serial;
    default: return nullptr;
  }
}

// The shared body of hdGet*v: fills `params` only on success (an error leaves it untouched).
template <typename T>
void get_values(const char* fn, HDenum pname, T* params, bool integer_only) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, std::string(fn) + " " + hex(pname), true);
  const Kind kind = kind_of(pname);
  if (kind == Kind::Unknown) return push_error(s, HD_INVALID_ENUM, s.current);
  if (kind == Kind::String || (integer_only && kind != Kind::Integer))
    return push_error(s, HD_INVALID_INPUT_TYPE, s.current);
  if (!params) return push_error(s, HD_INVALID_VALUE, s.current);
  Device* d = current_device(s);
  if (!d) return;
  std::vector<double> out;
  values(s, *d, pname, out);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if constexpr (std::is_same_v<T, HDboolean>)
      params[i] = out[i] != 0.0 ? HD_TRUE : HD_FALSE;
    else
      params[i] = static_cast<T>(out[i]);
  }
}

// The shared body of hdSet*v for real-valued parameters (force, torque).
template <typename T>
void set_values(const char* fn, HDenum pname, const T* params) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  const int count = set_count(pname);
  std::string line = std::string(fn) + " " + hex(pname);
  if (params) {
    char buf[64];
    for (int i = 0; i < count; ++i) {
      std::snprintf(buf, sizeof buf, " %g", static_cast<double>(params[i]));
      line += buf;
    }
  }
  log_line(s, std::move(line), true);
  if (count == 0) return push_error(s, HD_INVALID_ENUM, s.current);
  if constexpr (!std::is_floating_point_v<T>) {
    return push_error(s, HD_INVALID_INPUT_TYPE, s.current);
  } else {
    if (!params) return push_error(s, HD_INVALID_VALUE, s.current);
    Device* d = current_device(s);
    if (!d) return;
    // Stand-in's choice: forces and torques are set inside a frame of this device only.
    if (!d->in_frame) return push_error(s, HD_INVALID_OPERATION, d->handle);
    Vec3 v{};
    for (int i = 0; i < 3; ++i) {
      v[i] = static_cast<double>(params[i]);
      if (!std::isfinite(v[i])) return push_error(s, HD_INVALID_VALUE, d->handle);
    }
    if (pname == HD_CURRENT_FORCE) {
      d->f_frame = v;
      d->f_set = true;
    } else {
      // Gimbal torque (mN·m, §2.5) only on the 6DOF model; HD_CURRENT_TORQUE, deprecated
      // (§2.4), is taken as the same thing in the same unit, as CHAI3D uses it ([CHAI-HDP]
      // 957-961).
      if (!d->model->active_gimbal) return push_error(s, HD_INVALID_OPERATION, d->handle);
      d->t_frame = v;
      d->t_set = true;
    }
  }
}

// Clamps |v| to `limit`; true when it was above.
bool clamp_norm(Vec3& v, double limit) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n <= limit) return false;
  for (double& x : v) x *= limit / n;
  return true;
}

}  // namespace

// ============================== The vendor API (SOURCES.md §2.3) ==============================

FAKE_HD_EXPORT HHD hdInitDevice(HDstring pConfigName) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, pConfigName ? "hdInitDevice \"" + std::string(pConfigName) + "\""
                          : std::string("hdInitDevice NULL"),
           false);
  // HD_DEFAULT_DEVICE (NULL) "will initialize the first device that it finds" (§2.3).
  Device* d = pConfigName ? by_name(s, pConfigName) : (s.devices.empty() ? nullptr : &s.devices[0]);
  if (!d) {  // an invalid name: HD_DEVICE_FAULT (§2.3, [OH-REF] p.1-7)
    push_error(s, HD_DEVICE_FAULT, HD_INVALID_HANDLE);
    return HD_INVALID_HANDLE;
  }
  if (d->initialized) {  // §2.3, [OH-REF] p.1-7
    push_error(s, HD_DEVICE_ALREADY_INITIATED, d->handle);
    return HD_INVALID_HANDLE;
  }
  if (!d->plugged) {  // stand-in's choice: a device that does not answer
    push_error(s, HD_COMM_ERROR, HD_INVALID_HANDLE);
    return HD_INVALID_HANDLE;
  }
  d->initialized = true;
  d->handle = s.next_handle++;  // 0, 1, 2 ...: a new one per hdInitDevice
  reset_capabilities(*d);
  cut_forces(*d);
  d->in_frame = false;
  d->have_frame = false;
  s.current = d->handle;  // the new device is current (§2.3 canonical sequence relies on it)
  return d->handle;
}

FAKE_HD_EXPORT void hdDisableDevice(HHD hHD) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdDisableDevice " + std::to_string(hHD), false);
  Device* d = by_handle(s, hHD);
  if (!d) return push_error(s, HD_BAD_HANDLE, hHD);
  d->initialized = false;
  d->handle = HD_INVALID_HANDLE;
  d->in_frame = false;
  d->hang_pending = false;
  cut_forces(*d);
  // The plant moves only while the scheduler ticks, so no time passes between a release and the
  // next hdInitDevice; on the bench a stylus left alone is at rest long before. So a released
  // device is at rest where it was.
  d->v = Vec3{};
  d->gd = Vec3{};
  if (s.current == hHD) s.current = HD_INVALID_HANDLE;
}

FAKE_HD_EXPORT void hdMakeCurrentDevice(HHD hHD) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdMakeCurrentDevice " + std::to_string(hHD), true);
  if (!by_handle(s, hHD)) return push_error(s, HD_BAD_HANDLE, hHD);
  s.current = hHD;
}

FAKE_HD_EXPORT HHD hdGetCurrentDevice() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdGetCurrentDevice", true);
  return by_handle(s, s.current) ? s.current : HD_INVALID_HANDLE;
}

FAKE_HD_EXPORT void hdBeginFrame(HHD hHD) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdBeginFrame " + std::to_string(hHD), true);
  Device* d = by_handle(s, hHD);
  if (!d) return push_error(s, HD_BAD_HANDLE, hHD);
  if (d->hang_pending) {  // `hang`: block, without the lock, until `release` (or SECONDS)
    d->hang_pending = false;
    const double seconds = d->hang_seconds;
    const unsigned long release = s.release_gen, generation = s.generation;
    ++s.blocked;
    auto released = [&] { return s.release_gen != release; };
    if (seconds > 0)
      s.cv.wait_for(lock, std::chrono::duration<double>(seconds), released);
    else
      s.cv.wait(lock, released);
    --s.blocked;
    if (s.generation != generation) return push_error(s, HD_COMM_ERROR, hHD);  // `reset`
    d = by_handle(s, hHD);
    if (!d) return push_error(s, HD_BAD_HANDLE, hHD);
  }
  if (d->in_frame) return push_error(s, HD_ILLEGAL_BEGIN, hHD);
  // The frame opens even on an unplugged device (so that hdEndFrame pairs with it), but its
  // state is not refreshed and every call in it fails with HD_COMM_ERROR.
  d->in_frame = true;
  d->f_set = d->t_set = false;
  if (!d->plugged) return push_error(s, HD_COMM_ERROR, hHD);
  d->last = d->have_frame ? d->cur : snapshot(*d);
  d->cur = snapshot(*d);
  d->have_frame = true;
}

FAKE_HD_EXPORT void hdEndFrame(HHD hHD) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdEndFrame " + std::to_string(hHD), true);
  Device* d = by_handle(s, hHD);
  if (!d) return push_error(s, HD_BAD_HANDLE, hHD);
  if (!d->in_frame) return push_error(s, HD_ILLEGAL_END, hHD);
  d->in_frame = false;
  if (!d->plugged) return push_error(s, HD_COMM_ERROR, hHD);
  const bool output = d->caps[HD_FORCE_OUTPUT];
  // A frame that set no force leaves the force as it was (the stand-in's choice: a read-only
  // frame in the same tick does not cancel another callback's force).
  if (d->f_set) {
    Vec3 f = d->f_frame;
    if (!output) {
      f = {};
    } else {
      const double n = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      if (n > d->model->max_force) {
        push_error(s, HD_EXCEEDED_MAX_FORCE, hHD);  // 0x0201 (§2.4)
        if (d->caps[HD_MAX_FORCE_CLAMPING])
          clamp_norm(f, d->model->max_force);  // clamped to HD_NOMINAL_MAX_FORCE
        else
          f = {};  // stand-in's choice: without clamping, the frame's force is dropped
      }
    }
    d->f_out = f;
  }
  if (d->t_set) {
    for (int i = 0; i < 3; ++i) d->t_out[i] = output ? d->t_frame[i] / 1000.0 : 0.0;  // mN·m → N·m
  }
}

FAKE_HD_EXPORT HDErrorInfo hdGetError() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdGetError", true);
  if (t_errors.generation != s.generation) {
    t_errors.generation = s.generation;
    t_errors.errors.clear();
  }
  if (t_errors.errors.empty()) return HDErrorInfo{HD_SUCCESS, 0, HD_INVALID_HANDLE};
  const HDErrorInfo e = t_errors.errors.back();  // the most recent first (§2.3)
  t_errors.errors.pop_back();
  return e;
}

FAKE_HD_EXPORT HDstring hdGetErrorString(HDerror errorCode) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdGetErrorString " + hex(errorCode), true);
  return error_text(errorCode);
}

namespace {
bool is_capability(HDenum cap) {
  switch (cap) {
    case HD_FORCE_OUTPUT:
    case HD_MAX_FORCE_CLAMPING:
    case HD_FORCE_RAMPING:
    case HD_SOFTWARE_FORCE_LIMIT:
    case HD_ONE_FRAME_LIMIT:
    case HD_SOFTWARE_VELOCITY_LIMIT:
    case HD_SOFTWARE_FORCE_IMPULSE_LIMIT:
      return true;
    default:
      return false;
  }
}

void set_capability(const char* fn, HDenum cap, bool on) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, std::string(fn) + " " + hex(cap), false);
  if (!is_capability(cap)) return push_error(s, HD_INVALID_ENUM, s.current);
  Device* d = current_device(s);
  if (!d) return;
  d->caps[cap] = on;
  if (cap == HD_FORCE_OUTPUT && !on) cut_forces(*d);
}
}  // namespace

FAKE_HD_EXPORT void hdEnable(HDenum cap) { set_capability("hdEnable", cap, true); }
FAKE_HD_EXPORT void hdDisable(HDenum cap) { set_capability("hdDisable", cap, false); }

FAKE_HD_EXPORT HDboolean hdIsEnabled(HDenum cap) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdIsEnabled " + hex(cap), true);
  if (!is_capability(cap)) {
    push_error(s, HD_INVALID_ENUM, s.current);
    return HD_FALSE;
  }
  Device* d = current_device(s, /*allow_unplugged=*/true);
  if (!d) return HD_FALSE;
  return d->caps[cap] ? HD_TRUE : HD_FALSE;
}

FAKE_HD_EXPORT void hdGetBooleanv(HDenum pname, HDboolean* params) {
  get_values("hdGetBooleanv", pname, params, true);
}
FAKE_HD_EXPORT void hdGetIntegerv(HDenum pname, HDint* params) {
  get_values("hdGetIntegerv", pname, params, true);
}
FAKE_HD_EXPORT void hdGetFloatv(HDenum pname, HDfloat* params) {
  get_values("hdGetFloatv", pname, params, false);
}
FAKE_HD_EXPORT void hdGetDoublev(HDenum pname, HDdouble* params) {
  get_values("hdGetDoublev", pname, params, false);
}
FAKE_HD_EXPORT void hdGetLongv(HDenum pname, HDlong* params) {
  get_values("hdGetLongv", pname, params, true);
}

FAKE_HD_EXPORT HDstring hdGetString(HDenum pname) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdGetString " + hex(pname), false);
  const Kind kind = kind_of(pname);
  if (kind == Kind::Unknown) {
    push_error(s, HD_INVALID_ENUM, s.current);
    return nullptr;
  }
  if (kind != Kind::String) {
    push_error(s, HD_INVALID_INPUT_TYPE, s.current);
    return nullptr;
  }
  Device* d = current_device(s);
  if (!d) return nullptr;
  return string_of(*d, pname);
}

FAKE_HD_EXPORT void hdSetBooleanv(HDenum pname, const HDboolean* params) {
  set_values("hdSetBooleanv", pname, params);
}
FAKE_HD_EXPORT void hdSetIntegerv(HDenum pname, const HDint* params) {
  set_values("hdSetIntegerv", pname, params);
}
FAKE_HD_EXPORT void hdSetFloatv(HDenum pname, const HDfloat* params) {
  set_values("hdSetFloatv", pname, params);
}
FAKE_HD_EXPORT void hdSetDoublev(HDenum pname, const HDdouble* params) {
  set_values("hdSetDoublev", pname, params);
}
FAKE_HD_EXPORT void hdSetLongv(HDenum pname, const HDlong* params) {
  set_values("hdSetLongv", pname, params);
}

// ---- Calibration (§2.3; the loop of [ROS-OMNI] 245-273) ----

FAKE_HD_EXPORT HDenum hdCheckCalibration() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdCheckCalibration", true);
  Device* d = current_device(s);
  if (!d) return HD_CALIBRATION_NEEDS_UPDATE;
  return d->calibrated ? HD_CALIBRATION_OK : HD_CALIBRATION_NEEDS_UPDATE;
}

FAKE_HD_EXPORT HDenum hdCheckCalibrationStyle() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdCheckCalibrationStyle", false);
  Device* d = current_device(s);
  if (!d) return 0;
  return static_cast<HDenum>(d->model->calibration);  // the styles it supports, as the mask
}

FAKE_HD_EXPORT void hdUpdateCalibration(HDenum style) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdUpdateCalibration " + hex(style), false);
  Device* d = current_device(s);
  if (!d) return;
  // Stand-in's choice: one style the device supports calibrates it at once; anything else is
  // HD_INVALID_VALUE and changes nothing.
  const HDenum supported = static_cast<HDenum>(d->model->calibration);
  if (style == 0 || (style & (style - 1)) != 0 || (style & supported) == 0)
    return push_error(s, HD_INVALID_VALUE, d->handle);
  d->calibrated = true;
}

// ---- The scheduler (§2.3, hdScheduler.h) ----

FAKE_HD_EXPORT void hdStartScheduler() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdStartScheduler", false);
  if (s.started) return;
  if (s.servo.joinable() && s.servo.get_id() == std::this_thread::get_id()) {
    s.started = true;  // stopped and started again from inside a callback: the loop goes on
    s.stop = false;
    return;
  }
  if (s.servo.joinable()) {  // stopped from inside a callback: let it finish leaving first
    std::thread old = std::move(s.servo);
    lock.unlock();
    old.join();
    lock.lock();
    if (s.started) return;
  }
  for (Device& d : s.devices) cut_forces(d);
  s.started = true;
  s.stop = false;
  if (s.manual_clock) return;  // ticks come from `tick N` and hdScheduleSynchronous
  static std::once_flag at_exit;
  std::call_once(at_exit, [] { std::atexit(shutdown_scheduler); });
  s.servo_alive = true;
  s.servo = std::thread(servo_main, s.generation);
}

FAKE_HD_EXPORT void hdStopScheduler() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdStopScheduler", false);
  if (!s.started) return;
  s.started = false;
  // Forces flow only while the servo loop runs (§2.3: "forces are enabled when it starts").
  for (Device& d : s.devices) cut_forces(d);
  s.cv.notify_all();  // synchronous callers waiting on the servo thread
  if (!s.manual_clock) stop_servo_thread(s, lock, /*bounded=*/false);
}

FAKE_HD_EXPORT void hdSetSchedulerRate(HDulong nRate) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdSetSchedulerRate " + std::to_string(nRate), false);
  // §2.3, [OH-REF] p.3-4: 500, 1000, 2000 Hz (PCI, EPP); 500, 1000, 1600 Hz and
  // floor(8000/N + 0.5) (FireWire). The stand-in accepts all of these; any other rate is
  // HD_INVALID_VALUE.
  bool ok = nRate == 500 || nRate == 1000 || nRate == 1600 || nRate == 2000;
  for (unsigned long n = 1; n <= 8000 && !ok; ++n)
    ok = nRate == static_cast<HDulong>(std::floor(8000.0 / double(n) + 0.5));
  if (!ok) return push_error(s, HD_INVALID_VALUE, s.current);
  s.rate = nRate;
}

FAKE_HD_EXPORT void hdScheduleSynchronous(HDSchedulerCallback pCallback, void* pUserData,
                                          HDushort nPriority) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdScheduleSynchronous " + std::to_string(nPriority), true);
  if (!pCallback) return push_error(s, HD_INVALID_VALUE, s.current);
  // From the servo thread, or with no scheduler running: at once, on the caller's thread (§2.3:
  // callbacks submitted from the servo thread run immediately; before hdStartScheduler, or after
  // hdStopScheduler, the stand-in's choice).
  if (t_in_tick || !s.started) {
    lock.unlock();
    pCallback(pUserData);
    return;
  }
  if (s.entries.size() >= kMaxCallbacks) return push_error(s, HD_SCHEDULER_FULL, s.current);
  const unsigned long generation = s.generation;
  bool done = false;
  const HDSchedulerHandle h = s.next_sched++;
  if (s.manual_clock) {
    // The manual clock: this call runs one tick, here.
    wait_not_ticking(s, lock);
    if (s.generation != generation) return;
    if (!s.started) {  // stopped meanwhile
      lock.unlock();
      pCallback(pUserData);
      return;
    }
    s.entries.push_back(Entry{h, pCallback, pUserData, nPriority, s.next_seq++, true, &done});
    run_tick(s, lock);
    if (s.generation == generation) erase_entry(s, h);  // not run only if the tick was void
    return;
  }
  s.entries.push_back(Entry{h, pCallback, pUserData, nPriority, s.next_seq++, true, &done});
  s.cv.wait(lock, [&] {
    if (done || s.generation != generation) return true;
    const Entry* e = find_entry(s, h);
    return !s.started && !(e && e->running);
  });
  if (done || s.generation != generation) return;
  erase_entry(s, h);  // the scheduler stopped before it ran: run it here
  lock.unlock();
  pCallback(pUserData);
}

FAKE_HD_EXPORT HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback pCallback,
                                                        void* pUserData, HDushort nPriority) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdScheduleAsynchronous " + std::to_string(nPriority), true);
  if (!pCallback) {
    push_error(s, HD_INVALID_VALUE, s.current);
    return 0;
  }
  if (s.entries.size() >= kMaxCallbacks) {
    push_error(s, HD_SCHEDULER_FULL, s.current);
    return 0;
  }
  const HDSchedulerHandle h = s.next_sched++;
  if (t_in_tick) {
    // From the servo thread it runs at once (§2.3), then from the next tick while it continues.
    const unsigned long generation = s.generation;
    lock.unlock();
    const HDCallbackCode code = pCallback(pUserData);
    lock.lock();
    if (code != HD_CALLBACK_CONTINUE || s.generation != generation) return h;
  }
  s.entries.push_back(Entry{h, pCallback, pUserData, nPriority, s.next_seq++, false, nullptr});
  return h;
}

FAKE_HD_EXPORT void hdUnschedule(HDSchedulerHandle hHandle) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdUnschedule " + std::to_string(hHandle), false);
  Entry* e = find_entry(s, hHandle);
  if (!e || e->sync) return;  // not scheduled (any more): nothing to do
  if (!e->running) return erase_entry(s, hHandle);
  e->removed = true;
  if (t_in_tick) return;  // from its own callback: it is removed when it returns
  // Running on another thread: wait until it returns, so that its user data may be freed.
  s.cv.wait(lock, [&] { return find_entry(s, hHandle) == nullptr; });
}

FAKE_HD_EXPORT HDboolean hdWaitForCompletion(HDSchedulerHandle hHandle, HDWaitCode param) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdWaitForCompletion " + std::to_string(hHandle) + " " + std::to_string(param),
           true);
  if (param != HD_WAIT_CHECK_STATUS && param != HD_WAIT_INFINITE) {
    push_error(s, HD_INVALID_VALUE, s.current);
    return HD_FALSE;
  }
  auto scheduled = [&] { return find_entry(s, hHandle) != nullptr; };
  // HD_WAIT_INFINITE waits until the callback is done, unless no tick can come: inside a tick, or
  // with the scheduler stopped (stand-in's choice: it then answers at once).
  if (param == HD_WAIT_INFINITE && !t_in_tick) {
    const unsigned long generation = s.generation;
    s.cv.wait(lock, [&] { return !scheduled() || !s.started || s.generation != generation; });
  }
  return scheduled() ? HD_TRUE : HD_FALSE;  // "whether the callback is still scheduled"
}

FAKE_HD_EXPORT HDdouble hdGetSchedulerTimeStamp() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_line(s, "hdGetSchedulerTimeStamp", true);
  // "seconds since the start of the servo loop tick" (§2.3, [OH-REF] p.3-1): the current tick's,
  // or the last one's outside a tick.
  return std::chrono::duration<double>(Clock::now() - s.tick_start).count();
}

// ================================ The stand-in's control API ================================

FAKE_HD_EXPORT int fake_hd_control(const char* command) {
  if (!command) return -1;
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  const Words w = split(command);
  if (w.words.empty()) return -1;
  if (w.words[0] == "reset") {
    if (w.words.size() != 1 || t_in_tick || s.in_script) return -1;
    ++s.generation;  // void any tick in progress, every error stack and pending synchronous call
    ++s.release_gen;
    for (Device& d : s.devices) d.hang_pending = false;
    s.started = false;
    s.cv.notify_all();
    stop_servo_thread(s, lock, /*bounded=*/false);
    load_locked(s);
    run_script(s);  // the new script's items due at tick 0
    s.cv.notify_all();
    return 0;
  }
  if (w.words[0] == "tick") {
    long n = 0;
    char* end = nullptr;
    if (w.words.size() != 2) return -1;
    n = std::strtol(w.words[1].c_str(), &end, 10);
    if (*end != '\0' || n < 1 || !s.manual_clock || t_in_tick || s.in_script) return -1;
    const unsigned long generation = s.generation;
    for (long i = 0; i < n; ++i) {
      wait_not_ticking(s, lock);
      if (!s.started || s.generation != generation) return -1;  // no servo loop: no tick
      run_tick(s, lock);
    }
    return 0;
  }
  return control_locked(s, command);
}

FAKE_HD_EXPORT const char* fake_hd_calls() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  return s.log.text("fake_hd_calls");  // valid until the next fake_hd_calls/fake_hd_clear_calls
}

FAKE_HD_EXPORT void fake_hd_clear_calls() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  s.log.clear();
}

FAKE_HD_EXPORT int fake_hd_blocked() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  return s.blocked;
}

// ---- The definitions above have exactly the types declared in fake_openhaptics.hpp ----
#define FAKE_HD_CHECK(fn)                                      \
  static_assert(std::is_same_v<decltype(&fn), fake_hd::fn##_t>, \
                #fn " differs from its declared type")
FAKE_HD_CHECK(hdInitDevice);
FAKE_HD_CHECK(hdDisableDevice);
FAKE_HD_CHECK(hdMakeCurrentDevice);
FAKE_HD_CHECK(hdGetCurrentDevice);
FAKE_HD_CHECK(hdBeginFrame);
FAKE_HD_CHECK(hdEndFrame);
FAKE_HD_CHECK(hdGetError);
FAKE_HD_CHECK(hdGetErrorString);
FAKE_HD_CHECK(hdEnable);
FAKE_HD_CHECK(hdDisable);
FAKE_HD_CHECK(hdIsEnabled);
FAKE_HD_CHECK(hdGetBooleanv);
FAKE_HD_CHECK(hdGetIntegerv);
FAKE_HD_CHECK(hdGetFloatv);
FAKE_HD_CHECK(hdGetDoublev);
FAKE_HD_CHECK(hdGetLongv);
FAKE_HD_CHECK(hdGetString);
FAKE_HD_CHECK(hdSetBooleanv);
FAKE_HD_CHECK(hdSetIntegerv);
FAKE_HD_CHECK(hdSetFloatv);
FAKE_HD_CHECK(hdSetDoublev);
FAKE_HD_CHECK(hdSetLongv);
FAKE_HD_CHECK(hdCheckCalibration);
FAKE_HD_CHECK(hdCheckCalibrationStyle);
FAKE_HD_CHECK(hdUpdateCalibration);
FAKE_HD_CHECK(hdStartScheduler);
FAKE_HD_CHECK(hdStopScheduler);
FAKE_HD_CHECK(hdSetSchedulerRate);
FAKE_HD_CHECK(hdScheduleSynchronous);
FAKE_HD_CHECK(hdScheduleAsynchronous);
FAKE_HD_CHECK(hdUnschedule);
FAKE_HD_CHECK(hdWaitForCompletion);
FAKE_HD_CHECK(hdGetSchedulerTimeStamp);
FAKE_HD_CHECK(fake_hd_control);
FAKE_HD_CHECK(fake_hd_calls);
FAKE_HD_CHECK(fake_hd_clear_calls);
FAKE_HD_CHECK(fake_hd_blocked);
