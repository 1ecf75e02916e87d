// A stand-in for Force Dimension's runtime library (libdrd.so.3, which carries both the dhd* and
// the drd* functions, SOURCES.md §1.1), backed by a simulated plant, so that hapticd's Force
// Dimension driver can be loaded and exercised in ctest without the vendor's SDK or a device.
//
// Declarations are the project's own, written from the facts in driver/vendors/SOURCES.md §1 (see
// fake_forcedimension.hpp for every constant and its source). Behaviour the sources do not pin
// down is the stand-in's choice and is said so where it is made; README.md lists them.
//
// Control (for tests): fake_dhd_control("command ..."), fake_dhd_calls(), fake_dhd_clear_calls(),
// fake_dhd_blocked(); environment: FAKE_DHD_DEVICES, FAKE_DHD_SCRIPT.
#include "fake_forcedimension.hpp"
#include "standin_call_log.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#define FAKE_DHD_EXPORT extern "C" __attribute__((visibility("default")))

using namespace fake_dhd;

namespace {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<double, 9>;  // row-major, R(i,j) = m[3*i+j] (§1.6)

constexpr Mat3 kIdentity{1, 0, 0, 0, 1, 0, 0, 0, 1};

// ---- The plant's constants: the stand-in's own choices (no vendor figure exists for them) ----
constexpr double kDefaultDt = 0.001;          // s, one servo tick per force command
constexpr double kLinearDamping = 2.0;        // N·s/m per axis
constexpr double kBrakeDamping = 50.0;        // N·s/m added while braked
constexpr double kWristInertia = 1e-4;        // kg·m² per axis
constexpr double kWristDamping = 1e-3;        // N·m·s/rad per axis
constexpr double kWristBrakeDamping = 0.05;   // N·m·s/rad added while braked
constexpr double kGripperInertia = 1e-4;      // kg·m² (the angle's generalised inertia)
constexpr double kGripperDamping = 1e-3;      // N·m·s/rad
constexpr double kGripperOpen = 0.5;          // rad, start and upper limit; lower limit 0
constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = kStandardGravity;  // m/s², acting along -z of the device frame (§1.6)
constexpr double kDefaultVelocityLimit = 2.0;  // m/s per axis: the velocity guard's threshold (§1.6
                                               // "Safety"; no factory figure was found)

// ---- The models FAKE_DHD_DEVICES may name ----
struct Model {
  const char* name;     // FAKE_DHD_DEVICES spelling and dhdGetSystemName()
  int type;             // dhdGetSystemType()
  bool wrist, active_wrist, gripper, active_gripper;
  int buttons;
  bool left;            // dhdIsLeftHanded(): a left-handed model (type code *_LEFT, §1.5)
  double max_force;     // N (norm of the linear force)
  double max_torque;    // N·m (0: no actuated wrist)
  double max_gripper;   // N (0: no actuated gripper)
  double mass;          // kg (stand-in's choice)
  double half_box;      // m, workspace box ±half_box per axis
  bool needs_calibration;  // starts in RESET mode
  bool drd_supported;      // drdIsSupported(): the DRD can regulate (and so auto-calibrate) it
};

// Type codes: §1.5 ([CHAI-DHD] dhdc.h 88-106). Max force, torque, gripper force and workspace
// radius: §1.7, CHAI3D's table ([CHAI-DELTA] the lines given per row); the workspace radius is
// used as the half-width of a box. Wrist/gripper equipment follows the product names (omega.6:
// passive wrist; omega.7: + active gripper; sigma.7/lambda.7: active wrist + active gripper).
// Buttons: the Falcon's four (§1.5, [FDC] constants.py 107-114), one on the others (the stand-in's
// choice).
// The left-handed models (type codes *_LEFT, §1.5) are their right-handed twins mirrored; the
// Falcon is not one the DRD supports (drdIsSupported false: its regulation gains are not built in,
// [FDC] drd/__init__.py isSupported; the stand-in's choice for the Falcon, which DRD's CHAI3D
// users calibrate by hand).
// Fields: name, type, wrist, active wrist, gripper, active gripper, buttons, left-handed, max force
// N, max torque N·m, max gripper force N, mass kg, workspace half-box m, needs calibration, DRD.
constexpr Model kModels[] = {
    // §1.7, [CHAI-DELTA] lines 810-837
    {"omega.3", DHD_DEVICE_OMEGA3, false, false, false, false, 1, false, 12.0, 0, 0, 0.2, 0.075,
     true, true},
    // §1.7, [CHAI-DELTA] lines 842-899
    {"omega.6", DHD_DEVICE_OMEGA6_RIGHT, true, false, false, false, 1, false, 12.0, 0, 0, 0.2,
     0.075, true, true},
    // §1.7, [CHAI-DELTA] lines 904-960 (gripper 8.0 N)
    {"omega.7", DHD_DEVICE_OMEGA7_RIGHT, true, false, true, true, 1, false, 12.0, 0, 8.0, 0.2,
     0.075, true, true},
    {"omega.7-left", DHD_DEVICE_OMEGA7_LEFT, true, false, true, true, 1, true, 12.0, 0, 8.0, 0.2,
     0.075, true, true},
    // §1.7, [CHAI-DELTA] lines 968-1037 (torque 0.2 N·m, gripper 8.0 N)
    {"sigma.7", DHD_DEVICE_SIGMA7_RIGHT, true, true, true, true, 1, false, 12.0, 0.2, 8.0, 0.2,
     0.075, true, true},
    {"sigma.7-left", DHD_DEVICE_SIGMA7_LEFT, true, true, true, true, 1, true, 12.0, 0.2, 8.0, 0.2,
     0.075, true, true},
    // §1.7, [CHAI-DELTA] lines 778-805
    {"delta.3", DHD_DEVICE_DELTA3, false, false, false, false, 1, false, 20.0, 0, 0, 0.2, 0.15,
     true, true},
    // §1.7, [CHAI-DELTA] lines 1042-1126 (torque 0.2 N·m, gripper 8.0 N)
    {"lambda.7", DHD_DEVICE_LAMBDA7_RIGHT, true, true, true, true, 1, false, 12.0, 0.2, 8.0, 0.2,
     0.1125, true, true},
    // §1.7, [CHAI-DELTA] lines 1132-1158; no calibration at open (the stand-in's choice)
    {"falcon", DHD_DEVICE_FALCON, false, false, false, false, 4, false, 8.0, 0, 0, 0.1, 0.04,
     false, false},
};

const Model* find_model(const std::string& name) {
  for (const Model& m : kModels)
    if (name == m.name) return &m;
  return nullptr;
}

// Fixed English texts, one per code of §1.5 (the stand-in's own wording).
const char* const kErrorText[kErrorCount] = {
    "no error",                                  // 0
    "undefined error",                           // 1
    "communication error with the device",       // 2 COM
    "device controller busy",                    // 3
    "no driver found",                           // 4
    "no device found",                           // 5
    "feature not available on this device",      // 6
    "operation timed out",                       // 7
    "geometry error",                            // 8
    "expert mode disabled",                      // 9
    "function not implemented",                  // 10
    "out of memory",                             // 11
    "device not ready",                          // 12
    "file not found",                            // 13
    "configuration error",                       // 14
    "invalid index",                             // 15
    "deprecated function",                       // 16
    "null argument",                             // 17
    "redundant encoder check failed",            // 18
    "feature not enabled",                       // 19
    "device already in use",                     // 20
    "invalid argument",                          // 21
    "no regulation running",                     // 22
};

const char* error_text(int code) {
  if (code < 0 || code >= kErrorCount) return "unknown error";
  return kErrorText[code];
}

thread_local int t_last_error = DHD_NO_ERROR;  // per thread, §1.4

int fail(int code) {
  t_last_error = code;
  return -1;
}

struct Device {
  const Model* model = nullptr;
  unsigned short serial = 0;
  bool plugged = true;
  bool open = false;
  bool initialized = false;   // false = RESET mode (needs calibration)
  bool force = false;         // dhdEnableForce(1) in effect
  bool brake = false;         // BRAKE mode
  bool regulating = false;    // drdAutoInit's regulation holds the effector until drdStop
  bool gravity = true;        // gravity compensation on by default (§1.6, [FDC-DOCS] dhd-doc 260)
  // A force command has been sent since forces were last enabled: gravity compensation is computed
  // on the host and applied only with a force command (§1.6), so until then the arm falls.
  bool commanded = false;
  double velocity_limit = kDefaultVelocityLimit;  // m/s per axis, 0: off (`velocity ID LIMIT`)
  bool saturate = false;      // `saturate ID on`
  std::string failing;        // `fail ID FUNCTION [CODE]`: that force setter fails with failing_code
  int failing_code = DHD_ERROR_COM;
  int force_off_cause = DHD_FORCE_OFF_NONE;
  bool hang_pending = false;  // `hang ID`: the next position read blocks
  double hang_seconds = 0;    // 0: until `release`
  Vec3 p{}, v{}, hand{};
  Mat3 R = kIdentity;
  Vec3 w{};
  double grip = kGripperOpen, grip_v = 0;
  unsigned buttons = 0;
  Vec3 f_cmd{}, t_cmd{};      // last commanded (after clamping)
  double fg_cmd = 0;
};

struct ScriptItem {
  long tick;
  std::string command;
};

struct State {
  std::mutex mu;
  std::condition_variable cv;
  bool loaded = false;
  unsigned long generation = 0;      // bumped by `reset`
  unsigned long release_gen = 0;     // bumped by `release` and `reset`
  int blocked = 0;                   // calls blocked in a hang right now
  std::vector<Device> devices;
  int current = -1;                  // the default device
  double dt = kDefaultDt;
  long ticks = 0;                    // force-setting calls so far, any device
  std::vector<ScriptItem> script;
  std::size_t script_next = 0;
  bool in_script = false;            // a script item is running (it may not `reset`)
  int sdk[4] = {kSdkMajor, kSdkMinor, kSdkRelease, kSdkRevision};
  standin::CallLog log;
  bool logging = true;  // `log off`: calls are not logged (a test counting a driver's allocations)
};

// Never destroyed: a call may still be blocked in a hang when the process exits, and waiting on a
// destroyed condition variable (or glibc's destroy waiting for its waiters) must not happen. The
// library is linked with -z nodelete, so the pointer stays reachable.
State& state() {
  static State* s = new State;
  return *s;
}

// ---- Call log ----

void log_call(State& s, const char* name, std::initializer_list<double> args, bool countable) {
  if (!s.logging) return;
  std::string line = name;
  char buf[64];
  for (double a : args) {
    std::snprintf(buf, sizeof buf, " %g", a);
    line += buf;
  }
  s.log.add(std::move(line), countable);
}

double id_arg(char ID) { return static_cast<double>(static_cast<signed char>(ID)); }

// ---- Loading the configuration ----

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

int control_locked(State& s, const std::string& command);

// Runs the script items due after s.ticks force commands.
void run_script(State& s) {
  s.in_script = true;
  while (s.script_next < s.script.size() && s.script[s.script_next].tick <= s.ticks) {
    const std::string command = s.script[s.script_next++].command;
    if (control_locked(s, command) != 0)
      std::fprintf(stderr, "fake libdrd: FAKE_DHD_SCRIPT: '%s' failed at tick %ld\n",
                   command.c_str(), s.ticks);
  }
  s.in_script = false;
}

void load_locked(State& s) {
  s.devices.clear();
  s.current = -1;
  s.dt = kDefaultDt;
  s.logging = true;
  s.ticks = 0;
  s.script.clear();
  s.script_next = 0;
  s.sdk[0] = kSdkMajor, s.sdk[1] = kSdkMinor, s.sdk[2] = kSdkRelease, s.sdk[3] = kSdkRevision;
  s.log.clear();
  s.log.throw_from("");

  const char* env = std::getenv("FAKE_DHD_DEVICES");
  const std::string list = env ? env : "omega.3";
  std::stringstream in(list);
  std::string item;
  int index = 0;
  while (std::getline(in, item, ',')) {
    item = trim(item);
    if (item.empty()) continue;
    const Model* model = find_model(item);
    if (!model) {
      std::fprintf(stderr, "fake libdrd: FAKE_DHD_DEVICES: unknown model '%s' left out\n",
                   item.c_str());
      continue;
    }
    Device d;
    d.model = model;
    d.serial = model->type == DHD_DEVICE_FALCON ? kFalconSerial
                                                : static_cast<unsigned short>(kFirstSerial + index);
    d.initialized = !model->needs_calibration;
    s.devices.push_back(d);
    ++index;
  }

  const char* script = std::getenv("FAKE_DHD_SCRIPT");
  if (script) {
    std::stringstream sin(script);
    while (std::getline(sin, item, ';')) {
      item = trim(item);
      if (item.empty()) continue;
      char* end = nullptr;
      const long tick = std::strtol(item.c_str(), &end, 10);
      const std::string command = trim(end ? std::string(end) : std::string());
      if (end == item.c_str() || tick < 0 || command.empty()) {
        std::fprintf(stderr, "fake libdrd: FAKE_DHD_SCRIPT: bad item '%s' left out\n",
                     item.c_str());
        continue;
      }
      // Kept in order of tick (stable for equal ticks).
      auto at = s.script.begin();
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

// ---- Device resolution ----

// The open device `ID` names (-1: the default), or nullptr with the error set. An unplugged device
// fails with DHD_ERROR_COM unless `allow_unplugged`.
Device* device_for(State& s, char ID, bool allow_unplugged = false) {
  int id = static_cast<signed char>(ID);  // -1 on both signed- and unsigned-char targets (§1.2)
  if (id == -1) {
    id = s.current;
    if (id < 0) {
      fail(DHD_ERROR_NO_DEVICE_FOUND);
      return nullptr;
    }
  }
  if (id < 0 || id >= static_cast<int>(s.devices.size()) || !s.devices[id].open) {
    fail(DHD_ERROR_INVALID_INDEX);
    return nullptr;
  }
  Device& d = s.devices[id];
  if (!d.plugged && !allow_unplugged) {
    fail(DHD_ERROR_COM);
    return nullptr;
  }
  return &d;
}

int index_of(const State& s, const Device* d) { return static_cast<int>(d - s.devices.data()); }

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

// Rotation matrix of the rotation vector r (Rodrigues).
Mat3 rotation(const Vec3& r) {
  const double angle = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
  if (angle < 1e-15) return kIdentity;
  const double x = r[0] / angle, y = r[1] / angle, z = r[2] / angle;
  const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
          t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
          t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}

// Keeps R a rotation (Gram-Schmidt on its columns) against rounding drift.
void orthonormalize(Mat3& R) {
  Vec3 c0{R[0], R[3], R[6]}, c1{R[1], R[4], R[7]};
  auto norm = [](Vec3& u) {
    const double n = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& x : u) x /= n;
  };
  norm(c0);
  const double d = c0[0] * c1[0] + c0[1] * c1[1] + c0[2] * c1[2];
  for (int i = 0; i < 3; ++i) c1[i] -= d * c0[i];
  norm(c1);
  const Vec3 c2{c0[1] * c1[2] - c0[2] * c1[1], c0[2] * c1[0] - c0[0] * c1[2],
                c0[0] * c1[1] - c0[1] * c1[0]};
  R = {c0[0], c1[0], c2[0], c0[1], c1[1], c2[1], c0[2], c1[2], c2[2]};
}

// Commanded forces reach the plant only in FORCE mode: calibrated, forces enabled, not braked,
// plugged, and not held by drdAutoInit's regulation.
bool forces_applied(const Device& d) {
  return d.plugged && d.initialized && d.force && !d.brake && !d.regulating;
}

void step(Device& d, double dt) {
  const Model& m = *d.model;
  if (d.regulating) {  // drdAutoInit's regulation holds the effector still
    d.v = {};
    d.w = {};
    d.grip_v = 0;
    return;
  }
  const bool applied = forces_applied(d);
  // Gravity pulls the effector down (-z, §1.6's frame) unless the SDK's compensation holds it:
  // compensation on, forces applied, and a force command sent since they were enabled (the
  // compensation is computed on the host and sent with each force command, §1.6).
  const bool compensated = applied && d.gravity && d.commanded;
  const double b = kLinearDamping + (d.brake ? kBrakeDamping : 0.0);
  for (int i = 0; i < 3; ++i) {
    const double weight = i == 2 && !compensated ? -m.mass * kGravity : 0.0;
    const double F = (applied ? d.f_cmd[i] : 0.0) + d.hand[i] + weight;
    integrate(m.mass, b, F, dt, d.p[i], d.v[i]);
    if (d.p[i] > m.half_box) d.p[i] = m.half_box, d.v[i] = 0;
    if (d.p[i] < -m.half_box) d.p[i] = -m.half_box, d.v[i] = 0;
  }
  // The velocity guard (§1.6 "Safety"): an axis faster than the threshold while forces are on
  // turns them off and engages the brakes, within the step that passes it; dhdGetStatus then says
  // why (FORCE_OFF_CAUSE VELOCITY) until forces are enabled again.
  if (applied && d.velocity_limit > 0) {
    for (int i = 0; i < 3; ++i) {
      if (std::fabs(d.v[i]) > d.velocity_limit) {
        d.force = false;
        d.brake = true;
        d.force_off_cause = DHD_FORCE_OFF_VELOCITY;
        break;
      }
    }
  }
  if (m.active_wrist) {
    const double c = kWristDamping + (d.brake ? kWristBrakeDamping : 0.0);
    Vec3 dtheta{};
    for (int i = 0; i < 3; ++i)
      integrate(kWristInertia, c, applied ? d.t_cmd[i] : 0.0, dt, dtheta[i], d.w[i]);
    d.R = mul(rotation(dtheta), d.R);  // angular velocity in the base frame
    orthonormalize(d.R);
  }
  if (m.active_gripper) {
    const double c = kGripperDamping + (d.brake ? kWristBrakeDamping : 0.0);
    // d.grip is the opening; on a left-handed model the SDK's angle and force are its negatives.
    const double fg = m.left ? -d.fg_cmd : d.fg_cmd;
    integrate(kGripperInertia, c, applied ? fg : 0.0, dt, d.grip, d.grip_v);
    if (d.grip > kGripperOpen) d.grip = kGripperOpen, d.grip_v = 0;
    if (d.grip < 0) d.grip = 0, d.grip_v = 0;
  }
}

// ---- Control commands ----

bool parse_id(const State& s, std::istringstream& in, int& id) {
  if (!(in >> id)) return false;
  return id >= 0 && id < static_cast<int>(s.devices.size());
}

bool at_end(std::istringstream& in) {
  std::string extra;
  return !(in >> extra);
}

int control_locked(State& s, const std::string& command) {
  std::istringstream in(command);
  std::string verb;
  if (!(in >> verb)) return -1;
  int id = -1;
  if (verb == "reset") {
    if (!at_end(in) || s.in_script) return -1;
    ++s.generation;
    ++s.release_gen;
    s.cv.notify_all();
    load_locked(s);
    run_script(s);  // the new script's items due at tick 0
    t_last_error = DHD_NO_ERROR;
    return 0;
  }
  if (verb == "release") {
    if (!at_end(in)) return -1;
    for (Device& d : s.devices) d.hang_pending = false;
    ++s.release_gen;
    s.cv.notify_all();
    return 0;
  }
  if (verb == "throw") {  // `throw FUNCTION`: its calls throw from now on; `throw none` ends it
    std::string function;
    if (!(in >> function) || !at_end(in)) return -1;
    s.log.throw_from(function == "none" ? "" : function);
    return 0;
  }
  if (verb == "log") {  // `log off|on`: the call log allocates, which a driver's allocation test must not see
    std::string mode;
    if (!(in >> mode) || !at_end(in) || (mode != "on" && mode != "off")) return -1;
    s.logging = mode == "on";
    return 0;
  }
  if (verb == "dt") {
    double dt = 0;
    if (!(in >> dt) || !at_end(in) || !std::isfinite(dt) || dt <= 0 || dt > 1) return -1;
    s.dt = dt;
    return 0;
  }
  if (verb == "sdk") {
    int v[4];
    if (!(in >> v[0] >> v[1] >> v[2] >> v[3]) || !at_end(in)) return -1;
    for (int i = 0; i < 4; ++i) s.sdk[i] = v[i];
    return 0;
  }
  if (!parse_id(s, in, id)) return -1;
  Device& d = s.devices[id];
  if (verb == "unplug") {
    if (!at_end(in)) return -1;
    d.plugged = false;
    d.force = false;
    d.regulating = false;
    d.force_off_cause = DHD_FORCE_OFF_USBDISCN;  // §1.5 force-off causes
    return 0;
  }
  if (verb == "replug") {
    if (!at_end(in)) return -1;
    d.plugged = true;  // forces stay off until dhdEnableForce(1)
    return 0;
  }
  if (verb == "hang") {
    double seconds = 0;  // 0: until `release`
    std::string text;
    if (in >> text) {
      char* end = nullptr;
      seconds = std::strtod(text.c_str(), &end);
      if (end == text.c_str() || *end != '\0' || !at_end(in) || !std::isfinite(seconds) ||
          seconds < 0)
        return -1;
    }
    d.hang_pending = true;
    d.hang_seconds = seconds;
    return 0;
  }
  if (verb == "hand") {
    Vec3 f{};
    if (!(in >> f[0] >> f[1] >> f[2]) || !at_end(in)) return -1;
    for (double x : f)
      if (!std::isfinite(x)) return -1;
    d.hand = f;
    return 0;
  }
  if (verb == "turn") {
    Vec3 r{};
    if (!(in >> r[0] >> r[1] >> r[2]) || !at_end(in) || !d.model->wrist) return -1;
    for (double x : r)
      if (!std::isfinite(x)) return -1;
    d.R = rotation(r);
    d.w = {};
    return 0;
  }
  if (verb == "grip") {
    double a = 0;
    if (!(in >> a) || !at_end(in) || !d.model->gripper || !std::isfinite(a)) return -1;
    d.grip = std::fmin(kGripperOpen, std::fmax(0.0, a));
    d.grip_v = 0;
    return 0;
  }
  if (verb == "button") {
    std::string text;
    if (!(in >> text) || !at_end(in)) return -1;
    char* end = nullptr;
    const unsigned long mask = std::strtoul(text.c_str(), &end, 0);
    if (end == text.c_str() || *end != '\0') return -1;
    const int n = d.model->buttons;
    d.buttons = static_cast<unsigned>(mask) & (n >= 32 ? 0xffffffffu : ((1u << n) - 1u));
    return 0;
  }
  if (verb == "uncalibrate") {
    if (!at_end(in)) return -1;
    d.initialized = false;
    d.force = false;
    d.regulating = false;
    return 0;
  }
  if (verb == "forcebutton") {  // the device's force button: forces on -> off (BUTTON), off -> on
    if (!at_end(in)) return -1;
    if (forces_applied(d) || (d.force && d.initialized)) {
      d.force = false;
      d.brake = true;
      d.force_off_cause = DHD_FORCE_OFF_BUTTON;  // §1.5 force-off causes
    } else if (d.initialized && d.plugged) {
      d.force = true;
      d.brake = false;
      d.force_off_cause = DHD_FORCE_OFF_NONE;
      d.commanded = false;
    }
    return 0;
  }
  if (verb == "velocity") {  // the velocity guard's threshold, m/s per axis; 0 turns it off
    double limit = 0;
    if (!(in >> limit) || !at_end(in) || !std::isfinite(limit) || limit < 0) return -1;
    d.velocity_limit = limit;
    return 0;
  }
  if (verb == "elapse") {  // time passes without a force command: the plant steps under what it holds
    double seconds = 0;
    if (!(in >> seconds) || !at_end(in) || !std::isfinite(seconds) || seconds < 0 || seconds > 10)
      return -1;
    if (!d.plugged) return 0;
    for (long n = std::lround(seconds / s.dt); n > 0; --n) step(d, s.dt);
    return 0;
  }
  if (verb == "fail") {  // `fail ID FUNCTION [CODE]`: that force setter fails; `fail ID none`
    std::string name;
    int code = DHD_ERROR_COM;
    if (!(in >> name)) return -1;
    if (!(in >> code)) {
      if (!in.eof()) return -1;
    } else if (!at_end(in) || code <= DHD_NO_ERROR || code >= kErrorCount) {
      return -1;
    }
    if (name == "none") {
      d.failing.clear();
      return 0;
    }
    if (name != "dhdSetForce" && name != "dhdSetForceAndTorque" && name != "dhdSetForceAndGripperForce" &&
        name != "dhdSetForceAndTorqueAndGripperForce")
      return -1;
    d.failing = name;
    d.failing_code = code;
    return 0;
  }
  if (verb == "saturate") {
    std::string on;
    if (!(in >> on) || !at_end(in) || (on != "on" && on != "off")) return -1;
    d.saturate = on == "on";
    return 0;
  }
  return -1;
}

// ---- Shared bodies ----

int open_device(State& s, int id) {
  Device& d = s.devices[id];
  if (!d.plugged) return fail(DHD_ERROR_COM);
  d.open = true;
  s.current = id;
  return id;
}

int close_device(State& s, char ID) {
  Device* d = device_for(s, ID, /*allow_unplugged=*/true);
  if (!d) return -1;
  const int id = index_of(s, d);
  d->open = false;
  d->force = false;
  d->regulating = false;
  d->hang_pending = false;
  // The stand-in's plant moves only when forces are set, so no time passes between a close and
  // the next open; on the bench a reopen takes far longer than the unpowered arm takes to come to
  // rest. So a closed device is at rest where it was.
  d->v = Vec3{};
  d->w = Vec3{};
  d->grip_v = 0;
  if (s.current == id) {
    s.current = -1;
    for (int i = 0; i < static_cast<int>(s.devices.size()); ++i)
      if (s.devices[i].open) {
        s.current = i;
        break;
      }
  }
  return 0;
}

int open_first(State& s) {
  for (int i = 0; i < static_cast<int>(s.devices.size()); ++i)
    if (s.devices[i].plugged && !s.devices[i].open) return open_device(s, i);
  return fail(DHD_ERROR_NO_DEVICE_FOUND);
}

int open_id(State& s, char ID) {
  const int id = static_cast<signed char>(ID);
  if (id < 0 || id >= static_cast<int>(s.devices.size())) return fail(DHD_ERROR_NO_DEVICE_FOUND);
  return open_device(s, id);  // an open device gives its ID again ([FDC] openID docstring)
}

// Clamps |v| to `limit` (> 0); true when it did.
bool clamp_norm(Vec3& v, double limit) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n <= limit) return false;
  for (double& x : v) x *= limit / n;
  return true;
}

int set_forces(State& s, const char* name, Vec3 f, Vec3 t, double fg, char ID) {
  run_script(s);
  ++s.ticks;
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (d->failing == name) return fail(d->failing_code);  // `fail ID FUNCTION`: nothing sent
  for (double x : {f[0], f[1], f[2], t[0], t[1], t[2], fg})
    if (!std::isfinite(x)) return fail(DHD_ERROR_INVALID);
  const Model& m = *d->model;
  bool saturated = clamp_norm(f, m.max_force);
  if (m.active_wrist) {
    saturated |= clamp_norm(t, m.max_torque);
  } else {
    t = {};  // no actuated wrist: torque is ignored
  }
  if (m.active_gripper) {
    if (std::fabs(fg) > m.max_gripper) {
      fg = std::copysign(m.max_gripper, fg);
      saturated = true;
    }
  } else {
    fg = 0;
  }
  d->f_cmd = f;
  d->t_cmd = t;
  d->fg_cmd = fg;
  d->commanded = true;  // the host's gravity compensation goes out with this command (§1.6)
  step(*d, s.dt);
  return (saturated || d->saturate) ? DHD_MOTOR_SATURATED : 0;
}

// Blocks a position read while a `hang` is pending on the device, without holding the mutex.
// Returns the device again after the wait (or nullptr with the error set if it went away).
Device* wait_if_hung(State& s, std::unique_lock<std::mutex>& lock, Device* d, char ID) {
  if (!d->hang_pending) return d;
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
  if (s.generation != generation) {  // `reset` while blocked: the device is gone
    fail(DHD_ERROR_COM);
    return nullptr;
  }
  return device_for(s, ID);
}

void fill_status(const Device& d, int status[DHD_MAX_STATUS]) {
  for (int i = 0; i < DHD_MAX_STATUS; ++i) status[i] = 0;
  const Model& m = *d.model;
  status[DHD_STATUS_FORCE_OFF_CAUSE] = d.force_off_cause;
  status[DHD_STATUS_LOCKS] = -1;  // unknown (§1.5, [FDC] containers)
  status[DHD_STATUS_WRIST_DETECTED] = m.wrist ? 1 : 0;
  if (!d.plugged) return;  // not powered as far as the host can tell, not connected
  status[DHD_STATUS_POWER] = 1;
  status[DHD_STATUS_CONNECTED] = 1;
  status[DHD_STATUS_STARTED] = 1;
  status[DHD_STATUS_RESET] = d.initialized ? 0 : 1;
  status[DHD_STATUS_BRAKE] = d.brake ? 1 : 0;
  status[DHD_STATUS_FORCE] = d.initialized && d.force && !d.brake ? 1 : 0;
  status[DHD_STATUS_IDLE] = d.initialized && !d.brake && !d.force ? 1 : 0;
  status[DHD_STATUS_TORQUE] = m.active_wrist && status[DHD_STATUS_FORCE] ? 1 : 0;
  status[DHD_STATUS_GRAVITY] = d.gravity ? 1 : 0;
  status[DHD_STATUS_WRIST_INIT] = m.wrist && d.initialized ? 1 : 0;
}

template <typename Out>
bool all_set(std::initializer_list<Out*> outs) {
  for (Out* o : outs)
    if (!o) return false;
  return true;
}

const auto kStart = std::chrono::steady_clock::now();

}  // namespace

// ============================== The vendor API (SOURCES.md §1.3) ==============================

FAKE_DHD_EXPORT int dhdErrorGetLast() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdErrorGetLast", {}, true);
  return t_last_error;
}

FAKE_DHD_EXPORT const char* dhdErrorGetLastStr() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdErrorGetLastStr", {}, true);
  return error_text(t_last_error);
}

FAKE_DHD_EXPORT const char* dhdErrorGetStr(int error) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdErrorGetStr", {double(error)}, true);
  return error_text(error);
}

FAKE_DHD_EXPORT int dhdGetDeviceCount() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetDeviceCount", {}, false);
  return static_cast<int>(s.devices.size());
}

FAKE_DHD_EXPORT int dhdGetAvailableCount() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetAvailableCount", {}, false);
  int n = 0;
  for (const Device& d : s.devices) n += d.plugged && !d.open;
  return n;
}

FAKE_DHD_EXPORT int dhdSetDevice(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetDevice", {id_arg(ID)}, false);
  if (static_cast<signed char>(ID) == -1) return fail(DHD_ERROR_INVALID_INDEX);
  Device* d = device_for(s, ID, /*allow_unplugged=*/true);
  if (!d) return -1;
  s.current = index_of(s, d);
  return 0;
}

FAKE_DHD_EXPORT int dhdGetDeviceID() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetDeviceID", {}, true);
  return s.current;
}

FAKE_DHD_EXPORT int dhdGetSerialNumber(ushort* sn, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetSerialNumber", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!sn) return fail(DHD_ERROR_NULL_ARGUMENT);
  *sn = d->serial;
  return 0;
}

FAKE_DHD_EXPORT int dhdOpen() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdOpen", {}, false);
  return open_first(s);
}

FAKE_DHD_EXPORT int dhdOpenType(int type) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdOpenType", {double(type)}, false);
  for (int i = 0; i < static_cast<int>(s.devices.size()); ++i)
    if (s.devices[i].model->type == type && s.devices[i].plugged && !s.devices[i].open)
      return open_device(s, i);
  return fail(DHD_ERROR_NO_DEVICE_FOUND);
}

FAKE_DHD_EXPORT int dhdOpenSerial(int serial) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdOpenSerial", {double(serial)}, false);
  int found = -1;
  for (int i = 0; i < static_cast<int>(s.devices.size()); ++i) {
    const Device& d = s.devices[i];
    if (d.serial != serial || !d.plugged) continue;
    if (!d.open) return open_device(s, i);  // first one not yet open
    if (found < 0) found = i;
  }
  if (found >= 0) return open_device(s, found);  // already open: its ID again
  return fail(DHD_ERROR_NO_DEVICE_FOUND);
}

FAKE_DHD_EXPORT int dhdOpenID(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdOpenID", {id_arg(ID)}, false);
  return open_id(s, ID);
}

FAKE_DHD_EXPORT int dhdClose(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdClose", {id_arg(ID)}, false);
  return close_device(s, ID);
}

FAKE_DHD_EXPORT int dhdStop(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdStop", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  d->force = false;  // disables forces and puts the device in BRAKE mode ([FDC] stop docstring)
  d->brake = true;
  d->regulating = false;
  d->force_off_cause = DHD_FORCE_OFF_SOFTWARE;
  return 0;
}

FAKE_DHD_EXPORT int dhdEnableForce(uchar val, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdEnableForce", {double(val), id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (val) {
    // Stand-in's choice: a device still in RESET mode (not calibrated) refuses forces.
    if (!d->initialized) return fail(DHD_ERROR_DEVICE_NOT_READY);
    d->force = true;
    d->brake = false;
    d->force_off_cause = DHD_FORCE_OFF_NONE;
    d->commanded = false;  // no compensation until the next force command (§1.6)
  } else {
    // Forces off: BRAKE mode, "entered when forces are disabled" ([FDC-DOCS] dhd-doc, Device Modes).
    d->force = false;
    d->brake = true;
    d->force_off_cause = DHD_FORCE_OFF_SOFTWARE;
  }
  return 0;
}

FAKE_DHD_EXPORT int dhdGetSystemType(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetSystemType", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  return d->model->type;
}

FAKE_DHD_EXPORT const char* dhdGetSystemName(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetSystemName", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return nullptr;  // NULL on error (§1.4)
  return d->model->name;
}

FAKE_DHD_EXPORT void dhdGetSDKVersion(int* major, int* minor, int* release, int* revision) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetSDKVersion", {}, false);
  if (major) *major = s.sdk[0];
  if (minor) *minor = s.sdk[1];
  if (release) *release = s.sdk[2];
  if (revision) *revision = s.sdk[3];
}

FAKE_DHD_EXPORT int dhdGetStatus(int status[DHD_MAX_STATUS], char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetStatus", {id_arg(ID)}, true);
  Device* d = device_for(s, ID, /*allow_unplugged=*/true);
  if (!d) return -1;
  if (!status) return fail(DHD_ERROR_NULL_ARGUMENT);
  fill_status(*d, status);  // an unplugged device's status says so, and the call fails
  if (!d->plugged) return fail(DHD_ERROR_COM);
  return 0;
}

FAKE_DHD_EXPORT uint dhdGetButtonMask(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetButtonMask", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return 0;
  return d->buttons;
}

FAKE_DHD_EXPORT int dhdGetButton(int index, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetButton", {double(index), id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (index < 0 || index >= DHD_MAX_BUTTONS) return fail(DHD_ERROR_INVALID_INDEX);
  return (d->buttons >> index) & 1u;
}

#ifndef FAKE_DHD_NO_WRIST  // the equipment queries
namespace {
bool has(char ID, const char* name, bool Model::*field) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, name, {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return false;
  return d->model->*field;
}
}  // namespace

FAKE_DHD_EXPORT bool dhdHasWrist(char ID) { return has(ID, "dhdHasWrist", &Model::wrist); }
FAKE_DHD_EXPORT bool dhdHasActiveWrist(char ID) {
  return has(ID, "dhdHasActiveWrist", &Model::active_wrist);
}
FAKE_DHD_EXPORT bool dhdHasGripper(char ID) { return has(ID, "dhdHasGripper", &Model::gripper); }
FAKE_DHD_EXPORT bool dhdHasActiveGripper(char ID) {
  return has(ID, "dhdHasActiveGripper", &Model::active_gripper);
}

FAKE_DHD_EXPORT bool dhdIsLeftHanded(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdIsLeftHanded", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return false;
  return d->model->left;
}

#endif  // FAKE_DHD_NO_WRIST

FAKE_DHD_EXPORT int dhdSetGravityCompensation(int val, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetGravityCompensation", {double(val), id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  d->gravity = val != DHD_OFF;
  return 0;
}

FAKE_DHD_EXPORT int dhdSetBrakes(int val, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetBrakes", {double(val), id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  // BRAKE is the mode forces-off puts the device in ([FDC-DOCS] dhd-doc, Device Modes and
  // Electromagnetic Brakes); nothing documents the brakes taking a device out of FORCE mode, so in
  // FORCE mode this changes nothing (the stand-in's reading): dhdEnableForce(OFF) or dhdStop do.
  if (d->initialized && d->force && !d->regulating) return 0;
  d->brake = val != DHD_OFF;
  return 0;
}

FAKE_DHD_EXPORT int dhdGetPosition(double* px, double* py, double* pz, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetPosition", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!all_set({px, py, pz})) return fail(DHD_ERROR_NULL_ARGUMENT);
  d = wait_if_hung(s, lock, d, ID);
  if (!d) return -1;
  *px = d->p[0], *py = d->p[1], *pz = d->p[2];
  return 0;
}

FAKE_DHD_EXPORT int dhdGetLinearVelocity(double* vx, double* vy, double* vz, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetLinearVelocity", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!all_set({vx, vy, vz})) return fail(DHD_ERROR_NULL_ARGUMENT);
  *vx = d->v[0], *vy = d->v[1], *vz = d->v[2];
  return 0;
}

#ifndef FAKE_DHD_NO_WRIST  // the wrist and gripper getters
FAKE_DHD_EXPORT int dhdGetOrientationFrame(double matrix[3][3], char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetOrientationFrame", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!matrix) return fail(DHD_ERROR_NULL_ARGUMENT);
  const Mat3& R = d->model->wrist ? d->R : kIdentity;  // identity without a wrist (§1.6)
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) matrix[i][j] = R[3 * i + j];
  return 0;
}

FAKE_DHD_EXPORT int dhdGetPositionAndOrientationFrame(double* px, double* py, double* pz,
                                                      double matrix[3][3], char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetPositionAndOrientationFrame", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!all_set({px, py, pz}) || !matrix) return fail(DHD_ERROR_NULL_ARGUMENT);
  d = wait_if_hung(s, lock, d, ID);
  if (!d) return -1;
  *px = d->p[0], *py = d->p[1], *pz = d->p[2];
  const Mat3& R = d->model->wrist ? d->R : kIdentity;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) matrix[i][j] = R[3 * i + j];
  return 0;
}

FAKE_DHD_EXPORT int dhdGetAngularVelocityRad(double* wx, double* wy, double* wz, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetAngularVelocityRad", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!all_set({wx, wy, wz})) return fail(DHD_ERROR_NULL_ARGUMENT);
  *wx = d->w[0], *wy = d->w[1], *wz = d->w[2];  // zero unless the wrist is an active one
  return 0;
}

FAKE_DHD_EXPORT int dhdGetGripperAngleRad(double* a, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetGripperAngleRad", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!a) return fail(DHD_ERROR_NULL_ARGUMENT);
  if (!d->model->gripper) return fail(DHD_ERROR_NOT_AVAILABLE);
  *a = d->model->left ? -d->grip : d->grip;  // negative on a left-handed device (§1.6)
  return 0;
}

FAKE_DHD_EXPORT int dhdGetGripperAngleDeg(double* a, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetGripperAngleDeg", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!a) return fail(DHD_ERROR_NULL_ARGUMENT);
  if (!d->model->gripper) return fail(DHD_ERROR_NOT_AVAILABLE);
  *a = (d->model->left ? -d->grip : d->grip) * 180.0 / kPi;
  return 0;
}

#endif  // FAKE_DHD_NO_WRIST

FAKE_DHD_EXPORT int dhdSetForce(double fx, double fy, double fz, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetForce", {fx, fy, fz, id_arg(ID)}, true);
  return set_forces(s, "dhdSetForce", {fx, fy, fz}, {}, 0.0, ID);
}

#ifndef FAKE_DHD_NO_WRIST  // the wrist and gripper setters
FAKE_DHD_EXPORT int dhdSetForceAndTorque(double fx, double fy, double fz, double tx, double ty,
                                         double tz, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetForceAndTorque", {fx, fy, fz, tx, ty, tz, id_arg(ID)}, true);
  return set_forces(s, "dhdSetForceAndTorque", {fx, fy, fz}, {tx, ty, tz}, 0.0, ID);
}

FAKE_DHD_EXPORT int dhdSetForceAndGripperForce(double fx, double fy, double fz, double fg,
                                               char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetForceAndGripperForce", {fx, fy, fz, fg, id_arg(ID)}, true);
  return set_forces(s, "dhdSetForceAndGripperForce", {fx, fy, fz}, {}, fg, ID);
}

FAKE_DHD_EXPORT int dhdSetForceAndTorqueAndGripperForce(double fx, double fy, double fz, double tx,
                                                        double ty, double tz, double fg, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdSetForceAndTorqueAndGripperForce", {fx, fy, fz, tx, ty, tz, fg, id_arg(ID)},
           true);
  return set_forces(s, "dhdSetForceAndTorqueAndGripperForce", {fx, fy, fz}, {tx, ty, tz}, fg, ID);
}

FAKE_DHD_EXPORT int dhdGetForceAndTorqueAndGripperForce(double* fx, double* fy, double* fz,
                                                        double* tx, double* ty, double* tz,
                                                        double* fg, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetForceAndTorqueAndGripperForce", {id_arg(ID)}, true);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  if (!all_set({fx, fy, fz, tx, ty, tz, fg})) return fail(DHD_ERROR_NULL_ARGUMENT);
  *fx = d->f_cmd[0], *fy = d->f_cmd[1], *fz = d->f_cmd[2];  // last command, after clamping
  *tx = d->t_cmd[0], *ty = d->t_cmd[1], *tz = d->t_cmd[2];
  *fg = d->fg_cmd;
  return 0;
}

#endif  // FAKE_DHD_NO_WRIST

FAKE_DHD_EXPORT double dhdGetTime() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "dhdGetTime", {}, true);
  // Seconds, monotonic (§1.3, [FDC] dhd/os_independent.py 40-52); counted from the library's load.
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - kStart).count();
}

FAKE_DHD_EXPORT void dhdSleep(double sec) {
  {
    std::unique_lock<std::mutex> lock;
    State& s = loaded_state(lock);
    log_call(s, "dhdSleep", {sec}, true);
  }
  if (sec > 0 && std::isfinite(sec))
    std::this_thread::sleep_for(std::chrono::duration<double>(sec));
}

// ---- DRD (§1.3, [CHAI-DRD]) ----

FAKE_DHD_EXPORT int drdOpen() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdOpen", {}, false);
  return open_first(s);
}

FAKE_DHD_EXPORT int drdOpenID(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdOpenID", {id_arg(ID)}, false);
  return open_id(s, ID);
}

FAKE_DHD_EXPORT int drdClose(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdClose", {id_arg(ID)}, false);
  return close_device(s, ID);
}

FAKE_DHD_EXPORT bool drdIsInitialized(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdIsInitialized", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return false;
  return d->initialized;  // the controller's RESET LED (§1.3 semantics)
}

FAKE_DHD_EXPORT bool drdIsSupported(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdIsSupported", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return false;
  return d->model->drd_supported;
}

FAKE_DHD_EXPORT int drdAutoInit(char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdAutoInit", {id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  // A device the DRD does not support has no regulation to calibrate it with (the stand-in's
  // choice of error).
  if (!d->model->drd_supported) return fail(DHD_ERROR_NOT_AVAILABLE);
  // "moves to a known position and resets encoder counters" (§1.3): done at once, then the
  // regulation holds the effector at the origin, forces on, until drdStop.
  d->initialized = true;
  d->p = {};
  d->v = {};
  if (d->model->active_wrist) d->R = kIdentity;
  d->w = {};
  d->regulating = true;
  d->force = true;
  d->brake = false;
  d->force_off_cause = DHD_FORCE_OFF_NONE;
  return 0;
}

FAKE_DHD_EXPORT int drdStop(bool frc, char ID) {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  log_call(s, "drdStop", {frc ? 1.0 : 0.0, id_arg(ID)}, false);
  Device* d = device_for(s, ID);
  if (!d) return -1;
  d->regulating = false;
  d->commanded = false;  // the regulation's commands stop; the host has sent none
  if (!frc) {  // forces off unless the caller keeps them (CHAI3D: drdStop(true) then forces on)
    d->force = false;
    d->brake = true;
    d->force_off_cause = DHD_FORCE_OFF_SOFTWARE;
  }
  return 0;
}

// ================================ The stand-in's control API ================================

FAKE_DHD_EXPORT int fake_dhd_control(const char* command) {
  if (!command) return -1;
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  return control_locked(s, command);
}

FAKE_DHD_EXPORT const char* fake_dhd_calls() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  return s.log.text("fake_dhd_calls");  // valid until the next fake_dhd_calls/fake_dhd_clear_calls
}

FAKE_DHD_EXPORT void fake_dhd_clear_calls() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  s.log.clear();
}

FAKE_DHD_EXPORT int fake_dhd_blocked() {
  std::unique_lock<std::mutex> lock;
  State& s = loaded_state(lock);
  return s.blocked;
}

// ---- The definitions above have exactly the types declared in fake_forcedimension.hpp ----
#define FAKE_DHD_CHECK(fn)                                    \
  static_assert(std::is_same_v<decltype(&fn), fake_dhd::fn##_t>, \
                #fn " differs from its declared type")
FAKE_DHD_CHECK(dhdGetDeviceCount);
FAKE_DHD_CHECK(dhdGetAvailableCount);
FAKE_DHD_CHECK(dhdOpen);
FAKE_DHD_CHECK(dhdOpenID);
FAKE_DHD_CHECK(dhdOpenSerial);
FAKE_DHD_CHECK(dhdOpenType);
FAKE_DHD_CHECK(dhdClose);
FAKE_DHD_CHECK(dhdSetDevice);
FAKE_DHD_CHECK(dhdGetDeviceID);
FAKE_DHD_CHECK(dhdGetSystemType);
FAKE_DHD_CHECK(dhdGetSystemName);
FAKE_DHD_CHECK(dhdGetSerialNumber);
FAKE_DHD_CHECK(dhdGetSDKVersion);
FAKE_DHD_CHECK(dhdEnableForce);
FAKE_DHD_CHECK(dhdSetGravityCompensation);
FAKE_DHD_CHECK(dhdSetBrakes);
FAKE_DHD_CHECK(dhdStop);
FAKE_DHD_CHECK(dhdGetPosition);
FAKE_DHD_CHECK(dhdGetLinearVelocity);
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetOrientationFrame);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetPositionAndOrientationFrame);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetAngularVelocityRad);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetGripperAngleRad);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetGripperAngleDeg);
#endif
FAKE_DHD_CHECK(dhdGetButtonMask);
FAKE_DHD_CHECK(dhdGetButton);
FAKE_DHD_CHECK(dhdSetForce);
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdSetForceAndTorque);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdSetForceAndGripperForce);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdSetForceAndTorqueAndGripperForce);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdGetForceAndTorqueAndGripperForce);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdHasWrist);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdHasActiveWrist);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdHasGripper);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdHasActiveGripper);
#endif
#ifndef FAKE_DHD_NO_WRIST
FAKE_DHD_CHECK(dhdIsLeftHanded);
#endif
FAKE_DHD_CHECK(dhdGetStatus);
FAKE_DHD_CHECK(dhdErrorGetLast);
FAKE_DHD_CHECK(dhdErrorGetLastStr);
FAKE_DHD_CHECK(dhdErrorGetStr);
FAKE_DHD_CHECK(dhdGetTime);
FAKE_DHD_CHECK(dhdSleep);
FAKE_DHD_CHECK(drdOpen);
FAKE_DHD_CHECK(drdOpenID);
FAKE_DHD_CHECK(drdClose);
FAKE_DHD_CHECK(drdIsSupported);
FAKE_DHD_CHECK(drdIsInitialized);
FAKE_DHD_CHECK(drdAutoInit);
FAKE_DHD_CHECK(drdStop);
FAKE_DHD_CHECK(fake_dhd_control);
FAKE_DHD_CHECK(fake_dhd_calls);
FAKE_DHD_CHECK(fake_dhd_clear_calls);
FAKE_DHD_CHECK(fake_dhd_blocked);
