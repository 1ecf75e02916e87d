// A stand-in for Haply's Inverse Service (the local WebSocket service that the Inverse3 and
// VerseGrip are driven through, SOURCES.md §3.1), backed by a simulated plant, so that hapticd's
// Haply driver can be exercised in ctest without Haply's software or a device.
//
// The protocol facts are written from driver/vendors/SOURCES.md §3; the section is cited beside
// each. Behaviour the sources do not pin down is the stand-in's choice and is said so where it is
// made; README.md lists them.
//
// Two paths on one port: "/" is the simulation channel (§3.1, §3.2); "/control" is the tests'
// control channel (text commands, see control_impl), which is no part of Haply's protocol.
#include "fake_haply_service.hpp"

#include <nlohmann/json.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <future>
#include <map>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

namespace fake_haply {

namespace {

using json = nlohmann::ordered_json;
using Server = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;
using Vec3 = std::array<double, 3>;

constexpr std::size_t kLogMaxEntries = 50000;  // beyond this, messages are only counted

// The three device arrays of §3.2 (tutorial 00): inverse3, verse_grip, wireless_verse_grip.
enum class Kind { inverse3, verse_grip, wireless_verse_grip };
constexpr Kind kKinds[] = {Kind::inverse3, Kind::verse_grip, Kind::wireless_verse_grip};

const char* kind_name(Kind k) {
  switch (k) {
    case Kind::inverse3: return "inverse3";
    case Kind::verse_grip: return "verse_grip";
    case Kind::wireless_verse_grip: return "wireless_verse_grip";
  }
  return "?";
}

bool parse_kind(const std::string& name, Kind* k) {
  for (Kind kind : kKinds)
    if (name == kind_name(kind)) {
      *k = kind;
      return true;
    }
  return false;
}

struct Device {
  Kind kind = Kind::inverse3;
  std::string id;
  int index = 0;  // place among the devices of its kind (for the made-up serial port names)
  bool plugged = true;
  // Inverse3: the cursor (a point mass in Haply's frame, §3.4: +X right, +Y forward, +Z up; m).
  Vec3 p{kRestX, kRestY, kRestZ}, v{}, hand{};
  Vec3 f_cmd{};     // this message's commanded force, summed (§3.3: additive within a tick)
  Vec3 f_applied{}; // after clamping; reported as state.current_cursor_force
  bool commanded = false;  // a set_cursor_force arrived in this message
  // Grips: orientation as {w,x,y,z} (§3.4 quaternion), buttons (§3.2).
  std::array<double, 4> q{1, 0, 0, 0};
  bool a = false, b = false, c = false;  // wireless: state.buttons {a,b,c}; wired: a = state.button
  double battery = kBatteryLevel;
  // The tests' fault, no part of Haply's protocol: state.cursor_position.x sent as a string (a
  // service answering what a driver does not expect).
  bool garbled = false;
};

struct Client {
  bool control = false;  // a "/control" connection
  int session_id = 0;
};

struct LogEntry {
  std::string line;
  long count;
};

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

std::string fmt(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

json vec_json(const Vec3& v) { return json{{"x", v[0]}, {"y", v[1]}, {"z", v[2]}}; }
json quat_json(double w, double x, double y, double z) {
  return json{{"w", w}, {"x", x}, {"y", y}, {"z", z}};  // §3.4: quaternion {w,x,y,z}
}
json angles_json() { return json{{"a0", 0.0}, {"a1", 0.0}, {"a2", 0.0}}; }

// {"x":..,"y":..,"z":..} with three finite numbers (§3.4 vec3), or false with *why set.
bool read_vec(const json& j, Vec3* out, std::string* why) {
  if (!j.is_object()) {
    *why = "is not an object with x, y and z";
    return false;
  }
  static const char* const keys[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    auto it = j.find(keys[i]);
    if (it == j.end() || !it->is_number()) {
      *why = std::string("lacks a number ") + keys[i];
      return false;
    }
    (*out)[i] = it->get<double>();
    if (!std::isfinite((*out)[i])) {
      *why = std::string("has a non-finite ") + keys[i];
      return false;
    }
  }
  return true;
}

std::string join(const std::vector<std::string>& items, const char* sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

}  // namespace

struct Service::Impl {
  Options opt;
  Server server;
  std::thread thread;
  std::atomic<int> port{0};
  std::atomic<int> open_connections{0};
  bool started = false;

  // Touched only on the service's thread (every handler and every control command runs there).
  std::map<Hdl, Client, std::owner_less<Hdl>> clients;
  std::vector<Device> devices;
  double dt = kDefaultDt;
  bool stalled = false;
  std::deque<std::pair<Hdl, std::string>> held;  // messages received while stalled
  int next_session_id = 1;
  std::vector<LogEntry> log;
  long log_dropped = 0;

  // ---- Set-up ----

  bool parse_devices(const std::string& list, std::string* error) {
    devices.clear();
    std::stringstream in(list);
    std::string item;
    int counts[3] = {0, 0, 0};
    while (std::getline(in, item, ',')) {
      item = trim(item);
      if (item.empty()) continue;
      const auto colon = item.find(':');
      Device d;
      if (colon == std::string::npos || !parse_kind(trim(item.substr(0, colon)), &d.kind)) {
        *error = "bad device '" + item +
                 "' (expected inverse3:ID, verse_grip:ID or wireless_verse_grip:ID)";
        return false;
      }
      d.id = trim(item.substr(colon + 1));
      if (d.id.empty()) {
        *error = "device '" + item + "' has no id";
        return false;
      }
      for (const Device& other : devices)
        if (other.kind == d.kind && other.id == d.id) {
          *error = "device '" + item + "' listed twice";
          return false;
        }
      d.index = counts[static_cast<int>(d.kind)]++;
      devices.push_back(d);
    }
    return true;
  }

  // ---- The message log ("calls") ----

  void log_line(const std::string& line) {
    if (!log.empty() && log.back().line == line) {
      ++log.back().count;
      return;
    }
    if (log.size() >= kLogMaxEntries) {
      ++log_dropped;
      return;
    }
    log.push_back({line, 1});
  }

  std::string log_text() const {
    std::string out;
    for (const LogEntry& e : log) {
      out += e.line;
      if (e.count > 1) out += " x" + std::to_string(e.count);
      out += '\n';
    }
    if (log_dropped > 0) out += "(" + std::to_string(log_dropped) + " more not listed)\n";
    return out;
  }

  // ---- Devices ----

  Device* find(Kind kind, const std::string& id) {
    for (Device& d : devices)
      if (d.kind == kind && d.id == id) return &d;
    return nullptr;
  }

  // A control-channel device name: "ID" (the first device with that id) or "KIND:ID".
  Device* find_named(const std::string& name) {
    const auto colon = name.find(':');
    if (colon != std::string::npos) {
      Kind kind;
      if (!parse_kind(name.substr(0, colon), &kind)) return nullptr;
      return find(kind, name.substr(colon + 1));
    }
    for (Device& d : devices)
      if (d.id == name) return &d;
    return nullptr;
  }

  // ---- Messages out ----

  // config for one device (§3.2; the values the sources do not give are the stand-in's own).
  json config_json(const Device& d) const {
    if (d.kind == Kind::inverse3) {
      // §3.2, 3.5.x inventory example: the keys; handedness "right"; device_info.device_type 4;
      // id equal to device_id (§3.4). Versions, uuid, port and filter values are made up.
      char uuid[33];
      std::snprintf(uuid, sizeof uuid, "%032zx", std::hash<std::string>{}(d.id));
      json mount{{"position", vec_json({0, 0, 0})},
                 {"rotation", quat_json(1, 0, 0, 0)},
                 {"scale", 1.0}};
      return json{{"type", "inverse3"},
                  {"port", "/dev/ttyACM" + std::to_string(d.index)},
                  {"device_info",
                   {{"major_version", 1},
                    {"minor_version", 0},
                    {"id", d.id},
                    {"device_type", kInverse3DeviceType},
                    {"uuid", uuid}}},
                  {"extended_device_id", uuid},
                  {"extended_firmware_version", "fake-haply-service"},
                  {"gravity_compensation", {{"enabled", true}, {"scaling_factor", 1.0}}},
                  {"handedness", "right"},
                  {"streaming_mode", "USB"},
                  {"torque_scaling", {{"enabled", true}}},
                  {"home_return", {{"enabled", false}}},
                  {"preset", "defaults"},
                  {"basis", {{"permutation", "XYZ"}}},
                  {"mount", mount},
                  {"filters", {{"force_gate", {{"gain", 1.0}}}, {"damping", {{"scalar", 0.0}}}}}};
    }
    if (d.kind == Kind::verse_grip)  // §3.2, 3.4.x: config {port, type "verse_grip"}
      return json{{"port", "/dev/ttyUSB" + std::to_string(d.index)}, {"type", "verse_grip"}};
    // §3.2, 3.4.x HTTP /devices: {port, type "wireless_verse_grip", major_version,
    // minor_version, hardware_version}; the values are made up.
    return json{{"port", "/dev/ttyUSB" + std::to_string(d.index)},
                {"type", "wireless_verse_grip"},
                {"major_version", 1},
                {"minor_version", 0},
                {"hardware_version", 1}};
  }

  json state_json(const Device& d) const {
    if (d.kind == Kind::inverse3) {
      // §3.2, 3.5.x inventory example: the state's keys. No kinematics: the joint values are 0.
      // control_mode: "force" in a step with set_cursor_force, else "idle" (the stand-in's
      // reading of §3.3 "if you stop sending them, the device returns to idle").
      const Vec3 zero{};
      json position = vec_json(d.p);
      if (d.garbled) position["x"] = "not a number";
      return json{{"cursor_position", position},
                  {"cursor_velocity", vec_json(d.v)},
                  {"angular_position", angles_json()},
                  {"angular_velocity", angles_json()},
                  {"body_orientation", quat_json(1, 0, 0, 0)},
                  {"current_cursor_force", vec_json(d.f_applied)},
                  {"current_cursor_position", vec_json(d.p)},
                  {"current_angular_torques", angles_json()},
                  {"current_angular_position", angles_json()},
                  {"control_domain", "cartesian"},
                  {"control_mode", d.commanded ? "force" : "idle"},
                  {"transform",
                   {{"position", vec_json(zero)},
                    {"rotation", quat_json(1, 0, 0, 0)},
                    {"scale", vec_json({1, 1, 1})}}}};
    }
    const json orientation = quat_json(d.q[0], d.q[1], d.q[2], d.q[3]);
    if (d.kind == Kind::verse_grip)  // §3.2, 3.4.x: state {button, hall, orientation}
      return json{{"button", d.a}, {"hall", 0}, {"orientation", orientation}};
    // §3.2: wireless grips carry state.buttons {a,b,c} and orientation; battery_level (3.4.x).
    return json{{"orientation", orientation},
                {"buttons", {{"a", d.a}, {"b", d.b}, {"c", d.c}}},
                {"battery_level", d.battery}};
  }

  json status_json(const Device& d) const {
    if (d.kind == Kind::inverse3)  // §3.2, 3.4.x: status {calibrated, in_use, power_supply, ...}
      return json{{"calibrated", true},
                  {"in_use", true},
                  {"power_supply", true},
                  {"ready", true},
                  {"started", true}};
    return json{{"error", false}, {"ready", true}};  // §3.2, 3.4.x: grips' status {error, ready}
  }

  // A message with every plugged device's state and status (§3.2: "Later updates carry only
  // state and status"), and its config too when `full` (the initial inventory, or
  // session.force_render_full_state). All three arrays are always present, empty when no device
  // of that kind is plugged (the stand-in's choice). An unplugged device leaves its array.
  json devices_json(bool full) const {
    json out = json::object();
    for (Kind kind : kKinds) {
      json arr = json::array();
      for (const Device& d : devices) {
        if (d.kind != kind || !d.plugged) continue;
        json e{{"device_id", d.id}};
        if (full) e["config"] = config_json(d);
        e["state"] = state_json(d);
        e["status"] = status_json(d);
        arr.push_back(std::move(e));
      }
      out[kind_name(kind)] = std::move(arr);
    }
    return out;
  }

  void send(Hdl hdl, const std::string& text) {
    websocketpp::lib::error_code ec;
    server.send(hdl, text, websocketpp::frame::opcode::text, ec);
  }

  // ---- The plant ----

  // One step of dt for every plugged Inverse3: a point mass m with damping c per axis under the
  // (clamped) commanded force plus the hand force, integrated exactly (the mass-damper solution
  // for a force constant over the step).
  void step() {
    const double tau = kMass / kDamping;
    const double decay = std::exp(-dt / tau);
    for (Device& d : devices) {
      if (d.kind != Kind::inverse3) continue;
      if (!d.plugged) {
        d.f_applied = {};
        d.commanded = false;
        continue;  // an unplugged device does not move (the stand-in's choice)
      }
      Vec3 f = d.f_cmd;
      const double norm = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      if (norm > kMaxForce)
        for (double& x : f) x *= kMaxForce / norm;
      d.f_applied = f;
      for (int i = 0; i < 3; ++i) {
        const double v_inf = (f[i] + d.hand[i]) / kDamping;
        d.p[i] += v_inf * dt + (d.v[i] - v_inf) * tau * (1 - decay);
        d.v[i] = v_inf + (d.v[i] - v_inf) * decay;
      }
    }
  }

  // ---- The simulation channel ----

  void handle_session(const json& session, std::vector<std::string>& items,
                      std::vector<std::string>& errors, bool* full) {
    if (!session.is_object()) {
      errors.push_back("session is not an object");
      return;
    }
    for (auto it = session.begin(); it != session.end(); ++it) {
      if (it.key() == "configure") {  // §3.2: session.configure.profile.name on the first message
        std::string profile;
        if (it->is_object()) {
          auto p = it->find("profile");
          if (p != it->end() && p->is_object()) {
            auto n = p->find("name");
            if (n != p->end() && n->is_string()) profile = n->get<std::string>();
          }
        } else {
          errors.push_back("session.configure is not an object");
          continue;
        }
        // Recorded in the log; basis and other settings are accepted and not applied.
        std::string line = "session.configure";
        if (!profile.empty()) line += " profile=" + profile;
        for (auto k = it->begin(); k != it->end(); ++k)
          if (k.key() != "profile") line += " " + k.key();
        items.push_back(line);
      } else if (it.key() == "force_render_full_state") {  // §3.2 [HAPLY-sim 3.5.x]
        *full = true;
        items.push_back("session.force_render_full_state");
      } else {
        errors.push_back("unknown session key '" + it.key() + "'");
      }
    }
  }

  void handle_commands(Device& d, const json& commands, std::vector<std::string>& items,
                       std::vector<std::string>& errors) {
    const std::string who = std::string(kind_name(d.kind)) + " " + d.id;
    if (!commands.is_object()) {
      errors.push_back(who + ": commands is not an object");
      return;
    }
    for (auto it = commands.begin(); it != commands.end(); ++it) {
      const std::string& name = it.key();
      const json& body = it.value();
      if (d.kind == Kind::inverse3 && name == "set_cursor_force") {
        // §3.3: body {"vector": {x,y,z}} in the 3.5.x docs, {"values": {x,y,z}} in 3.1-era
        // clients; both are accepted. N, additive within a tick.
        Vec3 f{};
        std::string why;
        const json* vec = nullptr;
        if (body.is_object()) {
          if (body.contains("vector")) vec = &body["vector"];
          else if (body.contains("values")) vec = &body["values"];
        }
        if (!vec) {
          errors.push_back(who + ": set_cursor_force needs a vector (or values)");
          continue;
        }
        if (!read_vec(*vec, &f, &why)) {
          errors.push_back(who + ": set_cursor_force's vector " + why);
          continue;
        }
        for (int i = 0; i < 3; ++i) d.f_cmd[i] += f[i];
        d.commanded = true;
        items.push_back(who + " set_cursor_force " + fmt(f[0]) + " " + fmt(f[1]) + " " +
                        fmt(f[2]));
      } else if (d.kind == Kind::inverse3 && name == "probe_position") {  // §3.2, §3.3
        items.push_back(who + " probe_position");
      } else if (d.kind != Kind::inverse3 && name == "probe_orientation") {  // §3.2, §3.3
        items.push_back(who + " probe_orientation");
      } else if (d.kind == Kind::inverse3 &&
                 (name == "set_cursor_position" || name == "set_angular_torques" ||
                  name == "set_angular_position" || name == "set_transform")) {
        // §3.3 lists them; the stand-in refuses them (no position control or kinematics).
        errors.push_back(who + ": " + name + " is not supported by this stand-in");
        items.push_back(who + " " + name + " refused");
      } else {
        errors.push_back(who + ": unknown command '" + name + "'");
      }
    }
  }

  // One message in, exactly one message out (§3.2 core rule), after its commands are applied.
  void handle_message(Hdl hdl, const std::string& payload) {
    json in;
    try {
      in = json::parse(payload);
    } catch (const json::exception& e) {
      log_line("malformed");
      send(hdl, json{{"error", std::string("malformed JSON: ") + e.what()}}.dump());
      return;  // not applied: the plant does not step
    }
    if (!in.is_object()) {
      log_line("malformed");
      send(hdl, json{{"error", "malformed message: not a JSON object"}}.dump());
      return;
    }
    for (Device& d : devices) {
      d.f_cmd = {};
      d.commanded = false;
    }
    std::vector<std::string> items, errors;
    bool full = false;
    for (auto it = in.begin(); it != in.end(); ++it) {
      Kind kind;
      if (it.key() == "session") {
        handle_session(it.value(), items, errors, &full);
      } else if (parse_kind(it.key(), &kind)) {
        // §3.3: {"inverse3": [{"device_id": "...", "commands": {...}}]}; grips alike.
        if (!it->is_array()) {
          errors.push_back(it.key() + " is not an array");
          continue;
        }
        for (const json& entry : *it) {
          if (!entry.is_object() || !entry.contains("device_id") ||
              !entry["device_id"].is_string()) {
            errors.push_back(it.key() + ": an entry lacks a string device_id");
            continue;
          }
          const std::string id = entry["device_id"].get<std::string>();
          Device* d = find(kind, id);
          if (!d || !d->plugged) {
            errors.push_back(std::string(d ? "unplugged " : "unknown ") + "device " + it.key() +
                             " " + id);
            continue;
          }
          if (entry.contains("commands")) handle_commands(*d, entry["commands"], items, errors);
        }
      } else {
        errors.push_back("unknown key '" + it.key() + "'");
      }
    }
    step();
    std::string line = items.empty() ? std::string("empty") : join(items, "; ");
    if (!errors.empty()) line += " (error)";
    log_line(line);
    json out = devices_json(full);
    if (!errors.empty()) out["error"] = join(errors, "; ");
    send(hdl, out.dump());
  }

  // ---- The control channel ----

  std::string control_impl(const std::string& command) {
    std::stringstream in(command);
    std::string verb;
    in >> verb;
    auto rest_ok = [&in]() {
      std::string extra;
      return !(in >> extra);
    };
    auto numbers = [&in](double* out, int n) {
      for (int i = 0; i < n; ++i)
        if (!(in >> out[i]) || !std::isfinite(out[i])) return false;
      return true;
    };
    std::string name;
    if (verb == "hand") {
      double f[3];
      if (!(in >> name) || !numbers(f, 3) || !rest_ok()) return "error: usage: hand ID FX FY FZ";
      Device* d = find_named(name);
      if (!d || d->kind != Kind::inverse3) return "error: no inverse3 " + name;
      d->hand = {f[0], f[1], f[2]};
      return "ok";
    }
    if (verb == "button") {
      std::string which;
      int pressed = -1;
      if (!(in >> name >> which >> pressed) || (pressed != 0 && pressed != 1) || !rest_ok())
        return "error: usage: button GRIPID a|b|c 0|1";
      Device* d = find_named(name);
      if (!d || d->kind == Kind::inverse3) return "error: no grip " + name;
      if (d->kind == Kind::verse_grip) {  // one button (§3.2 state.button): any name sets it
        if (which != "a" && which != "b" && which != "c" && which != "button")
          return "error: button must be a, b or c";
        d->a = pressed;
        return "ok";
      }
      if (which == "a") d->a = pressed;
      else if (which == "b") d->b = pressed;
      else if (which == "c") d->c = pressed;
      else return "error: button must be a, b or c";
      return "ok";
    }
    if (verb == "orientation") {
      double q[4];
      if (!(in >> name) || !numbers(q, 4) || !rest_ok())
        return "error: usage: orientation GRIPID W X Y Z";
      Device* d = find_named(name);
      if (!d || d->kind == Kind::inverse3) return "error: no grip " + name;
      const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      if (norm < 1e-9) return "error: a zero quaternion";
      for (int i = 0; i < 4; ++i) d->q[i] = q[i] / norm;  // §3.4: unit length
      return "ok";
    }
    if (verb == "battery") {
      double level;
      if (!(in >> name) || !numbers(&level, 1) || !rest_ok() || level < 0 || level > 1)
        return "error: usage: battery GRIPID LEVEL (0..1)";
      Device* d = find_named(name);
      if (!d || d->kind != Kind::wireless_verse_grip) return "error: no wireless grip " + name;
      d->battery = level;
      return "ok";
    }
    if (verb == "unplug" || verb == "replug") {
      if (!(in >> name) || !rest_ok()) return "error: usage: " + verb + " ID";
      Device* d = find_named(name);
      if (!d) return "error: no device " + name;
      d->plugged = verb == "replug";
      d->v = {};  // at rest when it comes back
      return "ok";
    }
    if (verb == "garble" || verb == "ungarble") {
      if (!(in >> name) || !rest_ok()) return "error: usage: " + verb + " ID";
      Device* d = find_named(name);
      if (!d || d->kind != Kind::inverse3) return "error: no inverse3 " + name;
      d->garbled = verb == "garble";
      return "ok";
    }
    if (verb == "stall") {
      if (!rest_ok()) return "error: usage: stall";
      stalled = true;
      return "ok";
    }
    if (verb == "resume") {
      if (!rest_ok()) return "error: usage: resume";
      stalled = false;
      // The held messages are applied and answered now, in order, one step each.
      while (!stalled && !held.empty()) {
        auto [hdl, payload] = std::move(held.front());
        held.pop_front();
        if (clients.count(hdl)) handle_message(hdl, payload);
      }
      return "ok";
    }
    if (verb == "close") {
      if (!rest_ok()) return "error: usage: close";
      std::vector<Hdl> targets;
      for (const auto& [hdl, client] : clients)
        if (!client.control) targets.push_back(hdl);
      for (const Hdl& hdl : targets) {
        websocketpp::lib::error_code ec;
        server.close(hdl, websocketpp::close::status::going_away, "closed by the control channel",
                     ec);
      }
      return "ok";
    }
    if (verb == "calls") {
      if (!rest_ok()) return "error: usage: calls";
      return log_text();
    }
    if (verb == "clear") {
      if (!rest_ok()) return "error: usage: clear";
      log.clear();
      log_dropped = 0;
      return "ok";
    }
    if (verb == "clients") {
      if (!rest_ok()) return "error: usage: clients";
      int n = 0;
      for (const auto& entry : clients) n += entry.second.control ? 0 : 1;
      return std::to_string(n);
    }
    if (verb == "dt") {
      double s;
      if (!numbers(&s, 1) || !rest_ok() || s <= 0) return "error: usage: dt SECONDS (> 0)";
      dt = s;
      return "ok";
    }
    return "error: unknown command '" + verb + "'";
  }

  // ---- Connections ----

  static std::string path_of(const std::string& resource) {
    return resource.substr(0, resource.find('?'));
  }

  void on_open(Hdl hdl) {
    ++open_connections;
    auto con = server.get_con_from_hdl(hdl);
    Client c;
    c.control = path_of(con->get_resource()) == "/control";
    if (!c.control) {
      c.session_id = next_session_id++;
      log_line("connect");
    }
    clients[hdl] = c;
    if (c.control) return;
    // §3.2: on connect, the initial inventory with config, state and status for every device,
    // and a session_id (3.5.x).
    json inventory{{"session_id", c.session_id}};
    json devices_part = devices_json(true);
    for (auto it = devices_part.begin(); it != devices_part.end(); ++it)
      inventory[it.key()] = it.value();
    send(hdl, inventory.dump());
  }

  void on_close(Hdl hdl) {
    auto it = clients.find(hdl);
    if (it != clients.end()) {
      if (!it->second.control) {
        log_line("disconnect");
        // The plant steps only on messages, so no time passes between one client leaving and the
        // next arriving; on the bench the idle arm is at rest long before. So it is at rest here.
        for (Device& d : devices) d.v = Vec3{};
      }
      clients.erase(it);
      --open_connections;
    }
  }

  void on_message(Hdl hdl, Server::message_ptr msg) {
    auto it = clients.find(hdl);
    if (it == clients.end()) return;
    if (it->second.control) {
      send(hdl, control_impl(msg->get_payload()));
      return;
    }
    if (stalled) {  // answered on `resume`
      held.emplace_back(hdl, msg->get_payload());
      return;
    }
    handle_message(hdl, msg->get_payload());
  }
};

Service::Service(Options options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = std::move(options);
}

Service::~Service() { stop(); }

bool Service::start(std::string* error) {
  std::string scratch;
  if (!error) error = &scratch;
  Impl& s = *impl_;
  if (s.started) {
    *error = "already started";
    return false;
  }
  if (!(s.opt.dt > 0) || !std::isfinite(s.opt.dt)) {
    *error = "dt must be a positive number of seconds";
    return false;
  }
  if (!s.parse_devices(s.opt.devices, error)) return false;
  s.dt = s.opt.dt;
  try {
    s.server.clear_access_channels(websocketpp::log::alevel::all);
    s.server.clear_error_channels(websocketpp::log::elevel::all);
    s.server.init_asio();
    s.server.set_reuse_addr(true);
    s.server.set_socket_init_handler([](Hdl, asio::ip::tcp::socket& socket) {
      asio::error_code ec;
      socket.set_option(asio::ip::tcp::no_delay(true), ec);
    });
    // Only "/" (§3.1: ws://localhost:10001, no path) and "/control" are WebSocket endpoints.
    s.server.set_validate_handler([&s](Hdl hdl) {
      auto con = s.server.get_con_from_hdl(hdl);
      const std::string path = Impl::path_of(con->get_resource());
      if (path == "/" || path == "/control") return true;
      con->set_status(websocketpp::http::status_code::not_found);
      return false;
    });
    // Plain HTTP (§3.1's REST on the same port) is not modelled: 404.
    s.server.set_http_handler([&s](Hdl hdl) {
      auto con = s.server.get_con_from_hdl(hdl);
      con->set_status(websocketpp::http::status_code::not_found);
      con->set_body("{\"error\": \"HTTP is not modelled by fake-haply-service\"}");
      con->append_header("Content-Type", "application/json");
    });
    s.server.set_open_handler([&s](Hdl hdl) { s.on_open(hdl); });
    s.server.set_close_handler([&s](Hdl hdl) { s.on_close(hdl); });
    s.server.set_fail_handler([&s](Hdl hdl) { s.on_close(hdl); });
    s.server.set_message_handler(
        [&s](Hdl hdl, Server::message_ptr msg) { s.on_message(hdl, std::move(msg)); });
    asio::error_code aec;
    const auto address = asio::ip::make_address(s.opt.address, aec);
    if (aec) {
      *error = "bad address '" + s.opt.address + "'";
      return false;
    }
    websocketpp::lib::error_code ec;
    s.server.listen(asio::ip::tcp::endpoint(address, static_cast<unsigned short>(s.opt.port)),
                    ec);
    if (ec) {
      *error = "listen on " + s.opt.address + ":" + std::to_string(s.opt.port) + ": " +
               ec.message();
      return false;
    }
    s.server.start_accept(ec);
    if (ec) {
      *error = "accept: " + ec.message();
      return false;
    }
    const auto local = s.server.get_local_endpoint(aec);
    if (aec) {
      *error = "local endpoint: " + aec.message();
      return false;
    }
    s.port = local.port();
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  s.started = true;
  s.thread = std::thread([&s] {
    for (;;) {
      try {
        s.server.run();
        return;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "fake-haply-service: %s\n", e.what());
      }
    }
  });
  return true;
}

int Service::port() const { return impl_->port; }

std::string Service::control(const std::string& command) {
  Impl& s = *impl_;
  if (!s.started || !s.thread.joinable()) return "error: not running";
  auto promise = std::make_shared<std::promise<std::string>>();
  auto future = promise->get_future();
  asio::post(s.server.get_io_service(),
             [&s, promise, command] { promise->set_value(s.control_impl(command)); });
  if (future.wait_for(std::chrono::seconds(5)) != std::future_status::ready)
    return "error: the service did not answer within 5 s";
  return future.get();
}

void Service::stop() {
  Impl& s = *impl_;
  if (!s.thread.joinable()) return;
  asio::post(s.server.get_io_service(), [&s] {
    websocketpp::lib::error_code ec;
    s.server.stop_listening(ec);
    s.held.clear();
    std::vector<Hdl> all;
    for (const auto& entry : s.clients) all.push_back(entry.first);
    for (const Hdl& hdl : all)
      s.server.close(hdl, websocketpp::close::status::going_away, "service stopping", ec);
  });
  // Waits (bounded) for the clients to answer the close handshake, then stops the loop.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (s.open_connections > 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  s.server.stop();
  s.thread.join();
}

}  // namespace fake_haply
