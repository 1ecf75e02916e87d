// hapticd's driver for the Haply Inverse3 (with its VerseGrip handle) through Haply's Inverse
// Service: a local WebSocket service (ws://127.0.0.1:10001), JSON both ways. Built against
// <haptic/driver.h> alone plus Debian's header-only websocketpp over standalone Asio (C++17: the
// library does not compile as C++20) and nlohmann/json.
//
// The protocol is written from the public facts in driver/vendors/SOURCES.md, section 3 ("§3.x"):
// on connecting the service sends an inventory of every device; after that it answers each message
// with exactly one state message (§3.2). Commands are per message, not persistent (§3.3), so the
// driver sends one a tick: hapticd's write() sends the force (set_cursor_force) and the service's
// answer is the sample the next read() takes (one tick and a round trip on loopback of delay).
//
// The device at its tool point in W, the frame every hapticd vendor driver uses: x towards the
// operator, y to the right, z up. Haply's frame is +X right, +Y forward, +Z up (§3.4), so
// W = (-Y, X, Z); metres, m/s and N both sides (§3.4).
//
// params (all optional):
//   "url": the service (default ws://127.0.0.1:10001, §3.1)
//   "device_id": the Inverse3 to drive (default: the first in the inventory, §3.4)
//   "grip_id": the VerseGrip whose orientation and buttons to report (default: the first
//              wireless_verse_grip, else the first verse_grip; "" for none)
//   "force_key": "vector" (the 3.5 documentation) or "values" (3.1-era clients): the member of
//              set_cursor_force holding the force (§3.3 notes the two disagree)
//   "max_force" (N, default 3: Haply publishes no figure, §3.4: a conservative default; set it
//              from the device's manual), "workspace_radius" (m, default 0.10, the tutorial's
//              clamp radius, §3.4: not a specification), centred on the cursor at start
//   "reply_timeout_ms" (default 5): how long read() waits for the service's answer
//   "apparent_mass", "apparent_damping": [x, y, z] (kg, N·s/m), from one's own identification
// The JSON it exchanges allocates: keep the default call timeout (calls on the driver thread), not
// 0 (on the loop).
#include <haptic/driver.h>

#define ASIO_STANDALONE
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <atomic>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/driver_params.hpp"
#include "common/driver_adapter.hpp"

namespace {

using Json = nlohmann::json;
using WsClient = websocketpp::client<websocketpp::config::asio_client>;

constexpr const char* kDefaultUrl = "ws://127.0.0.1:10001";  // §3.1: the simulation channel

/// Haply's frame (+X right, +Y forward, +Z up) to W (x towards the operator, y right, z up).
void to_w(const Json& v, double w[3]) {
  w[0] = -v.value("y", 0.0);
  w[1] = v.value("x", 0.0);
  w[2] = v.value("z", 0.0);
}

/// The member `key` of an object, or an empty object when there is none.
const Json& member(const Json& object, const char* key) {
  static const Json kNone = Json::object();
  if (!object.is_object()) return kNone;
  const auto found = object.find(key);
  return found != object.end() ? *found : kNone;
}

/// One connection to the service, its messages handed to whoever waits for them.
class Connection {
 public:
  Connection() {
    client_.clear_access_channels(websocketpp::log::alevel::all);
    client_.clear_error_channels(websocketpp::log::elevel::all);
    client_.init_asio();
    client_.set_open_handler([this](websocketpp::connection_hdl handle) {
      std::lock_guard lock(mutex_);
      handle_ = handle;
      open_ = true;
      changed_.notify_all();
    });
    client_.set_fail_handler([this](websocketpp::connection_hdl) {
      std::lock_guard lock(mutex_);
      failed_ = true;
      changed_.notify_all();
    });
    client_.set_close_handler([this](websocketpp::connection_hdl) {
      std::lock_guard lock(mutex_);
      open_ = false;
      failed_ = true;
      changed_.notify_all();
    });
    client_.set_message_handler([this](websocketpp::connection_hdl, WsClient::message_ptr message) {
      std::lock_guard lock(mutex_);
      latest_ = message->get_payload();
      ++received_;
      changed_.notify_all();
    });
  }
  ~Connection() { close(); }

  /// Connects within `timeout`; empty on success, else why not.
  std::string open(const std::string& url, std::chrono::milliseconds timeout) {
    websocketpp::lib::error_code error;
    WsClient::connection_ptr connection = client_.get_connection(url, error);
    if (error) return "params.url '" + url + "': " + error.message();
    client_.connect(connection);
    thread_ = std::thread([this] { client_.run(); });
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, timeout, [this] { return open_ || failed_; });
    if (!open_) return "no Haply Inverse Service answers at " + url;
    return {};
  }

  bool send(const std::string& text) {
    websocketpp::lib::error_code error;
    std::lock_guard lock(mutex_);
    if (!open_) return false;
    client_.send(handle_, text, websocketpp::frame::opcode::text, error);
    return !error;
  }

  /// Waits until more than `seen` messages have arrived (or `timeout`); the newest then, or
  /// nothing. `seen` becomes the count.
  bool wait_newer(std::uint64_t& seen, std::chrono::microseconds timeout, std::string& message) {
    std::unique_lock lock(mutex_);
    if (!changed_.wait_for(lock, timeout, [&] { return received_ > seen || failed_; }) || received_ <= seen) {
      return false;
    }
    seen = received_;
    message = latest_;
    return true;
  }

  bool connected() {
    std::lock_guard lock(mutex_);
    return open_;
  }

  void close() {
    {
      std::lock_guard lock(mutex_);
      if (open_) {
        websocketpp::lib::error_code error;
        client_.close(handle_, websocketpp::close::status::normal, "hapticd stops", error);
      }
    }
    client_.stop();
    if (thread_.joinable()) thread_.join();
  }

 private:
  WsClient client_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  websocketpp::connection_hdl handle_;
  bool open_ = false, failed_ = false;
  std::string latest_;
  std::uint64_t received_ = 0;
};

/// One Inverse3 (and its grip) through the service: the driver's device (common/driver_adapter.hpp).
struct Device : haptic::vendor::VendorDevice {
  static constexpr const char* kParams[] = {"url",           "device_id",        "grip_id",
                                            "force_key",     "max_force",        "workspace_radius",
                                            "reply_timeout_ms", "apparent_mass", "apparent_damping"};
  static constexpr bool kDeviceClocked = false;  // the service answers each message: no clock to lend

  HAPTIC_VENDOR_DEVICE(Device);

  std::string url, device_id, grip_id, grip_kind, force_key = "vector";
  double max_force = 3.0, workspace_radius = 0.10;
  double centre_W[3] = {0, 0, 0};
  double apparent_mass[3] = {0, 0, 0}, apparent_damping[3] = {0, 0, 0};
  std::chrono::microseconds reply_timeout{5000};
  std::unique_ptr<Connection> connection;
  std::uint64_t seen = 0;      // messages taken so far
  std::uint64_t sequence = 0;  // samples given to hapticd
  std::string session_name = "hapticd";
  // Whether the session's configuration went out: the loop's write and another thread's
  // enter_safe_state may build a message at once, and exactly one of them must carry it.
  std::atomic<bool> session_sent{false};
  // Each enter_safe_state moves it on, under `send_mutex` with its message: a write that began
  // before it (a late one, beside hapticd's watchdog) sends nothing after the safe state's message.
  std::atomic<std::uint64_t> safe_epoch{0};
  std::mutex send_mutex;
  // The newest sample, from the service's newest answer.
  double position_W[3] = {0, 0, 0}, velocity_W[3] = {0, 0, 0}, orientation_W[4] = {1, 0, 0, 0};
  std::uint32_t buttons = 0;
  std::string failure;  // the most recent failure, for last_error (written and read under `failure_mutex`)
  mutable std::mutex failure_mutex;

  void fail(const std::string& why) {
    std::lock_guard lock(failure_mutex);
    failure = why;
  }
};

/// The device's entry in a message's array `kind` (inverse3, verse_grip, ...), or null.
const Json* find_device(const Json& message, const std::string& kind, const std::string& id) {
  const auto list = message.find(kind);
  if (list == message.end() || !list->is_array()) return nullptr;
  for (const Json& entry : *list) {
    if (entry.value("device_id", std::string()) == id) return &entry;
  }
  return nullptr;
}

/// The first device id in a message's array `kind`; empty when there is none.
std::string first_id(const Json& message, const std::string& kind) {
  const auto list = message.find(kind);
  if (list == message.end() || !list->is_array() || list->empty()) return {};
  return list->front().value("device_id", std::string());
}

/// Takes a state message into the device's sample; false (with the reason kept) when it lacks the
/// device.
bool take(Device& device, const std::string& text) {
  const Json message = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded() || !message.is_object()) {
    device.fail("the service sent what is not a JSON object");
    return false;
  }
  if (message.contains("error")) {
    // Replacing what is not UTF-8 rather than throwing on it: the text goes into an error message.
    device.fail("the service refused: " + message["error"].dump(-1, ' ', false, Json::error_handler_t::replace));
    return false;
  }
  const Json* arm = find_device(message, "inverse3", device.device_id);
  if (arm == nullptr) {
    device.fail("the Inverse3 " + device.device_id + " is not in the service's state (unplugged?)");
    return false;
  }
  const Json& state = member(*arm, "state");
  to_w(member(state, "cursor_position"), device.position_W);
  to_w(member(state, "cursor_velocity"), device.velocity_W);
  if (!device.grip_id.empty()) {
    if (const Json* grip = find_device(message, device.grip_kind, device.grip_id)) {
      const Json& g = member(*grip, "state");
      const Json& q = member(g, "orientation");  // {w, x, y, z} (§3.2), in Haply's frame
      if (q.contains("w")) {
        device.orientation_W[0] = q.value("w", 1.0);
        device.orientation_W[1] = -q.value("y", 0.0);  // the vector part turns like a vector
        device.orientation_W[2] = q.value("x", 0.0);
        device.orientation_W[3] = q.value("z", 0.0);
      }
      const Json& buttons = member(g, "buttons");
      if (!buttons.empty()) {  // the wireless grip's a, b, c (§3.2)
        device.buttons = (buttons.value("a", false) ? 1u : 0u) | (buttons.value("b", false) ? 2u : 0u) |
                         (buttons.value("c", false) ? 4u : 0u);
      } else {
        device.buttons = g.value("button", false) ? 1u : 0u;  // the wired grip's one (§3.2)
      }
    }
  }
  {
    std::lock_guard lock(device.failure_mutex);
    device.failure.clear();
  }
  return true;
}

/// A message for the Inverse3: `commands` (an object), with the session's configuration the first
/// time (§3.2: its handshake).
std::string command_message(Device& device, Json commands) {
  Json message = Json::object();
  if (!device.session_sent.exchange(true)) {
    message["session"] = {{"configure", {{"profile", {{"name", device.session_name}}}}}};
  }
  message["inverse3"] = Json::array({{{"device_id", device.device_id}, {"commands", std::move(commands)}}});
  return message.dump();
}

std::string probe(Device& device) {
  return command_message(device, {{"probe_position", Json::object()}});
}

std::unique_ptr<Device> Device::open(const haptic::vendor::DriverParams& params) {
  using haptic::vendor::Refusal;
  auto device = std::make_unique<Device>();
  device->url = params.text("url").value_or(kDefaultUrl);
  device->force_key = params.text("force_key").value_or("vector");
  if (device->force_key != "vector" && device->force_key != "values") {
    throw Refusal("params.force_key: \"vector\" or \"values\", got \"" + device->force_key + "\"");
  }
  device->max_force = params.number("max_force").value_or(3.0);
  device->workspace_radius = params.number("workspace_radius").value_or(0.10);
  if (!(device->max_force > 0.0) || !(device->workspace_radius > 0.0)) {
    throw Refusal("params.max_force and params.workspace_radius must be > 0");
  }
  device->reply_timeout = std::chrono::microseconds(
      static_cast<long>(1000.0 * params.number("reply_timeout_ms").value_or(5.0)));
  if (auto m = params.triple("apparent_mass")) std::copy(m->begin(), m->end(), device->apparent_mass);
  if (auto b = params.triple("apparent_damping")) std::copy(b->begin(), b->end(), device->apparent_damping);
  device->connection = std::make_unique<Connection>();
  if (std::string why = device->connection->open(device->url, std::chrono::milliseconds(2000)); !why.empty()) {
    throw Refusal(why + ": is the Haply Inverse Service running (Haply Hub, or systemctl start "
                        "haply-inverse-service)?");
  }
  // The inventory comes first (§3.2): choose the devices from it.
  std::string text;
  if (!device->connection->wait_newer(device->seen, std::chrono::seconds(2), text)) {
    throw Refusal("the Haply Inverse Service at " + device->url + " sent no inventory within 2 s");
  }
  const Json inventory = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (inventory.is_discarded() || !inventory.is_object()) {
    throw Refusal("the Haply Inverse Service's inventory is not a JSON object");
  }
  const std::string first = first_id(inventory, "inverse3");
  if (first.empty()) throw Refusal("the Haply Inverse Service lists no Inverse3: is one connected and powered?");
  device->device_id = params.text("device_id").value_or(first);
  if (find_device(inventory, "inverse3", device->device_id) == nullptr) {
    std::string ids;
    for (const Json& arm : inventory["inverse3"]) ids += (ids.empty() ? "" : ", ") + arm.value("device_id", std::string());
    throw Refusal("params.device_id \"" + device->device_id + "\": the service lists " + ids);
  }
  if (auto grip = params.text("grip_id")) {
    device->grip_id = *grip;
    device->grip_kind = find_device(inventory, "wireless_verse_grip", *grip) != nullptr ? "wireless_verse_grip"
                                                                                         : "verse_grip";
  } else {
    for (const char* kind : {"wireless_verse_grip", "verse_grip"}) {
      if (std::string id = first_id(inventory, kind); !id.empty()) {
        device->grip_id = id;
        device->grip_kind = kind;
        break;
      }
    }
  }
  if (!take(*device, text)) {
    std::lock_guard lock(device->failure_mutex);
    throw Refusal(device->failure);
  }
  std::copy(device->position_W, device->position_W + 3, device->centre_W);
  return device;
}

void Device::describe(haptic_driver_info& info) const {
  std::snprintf(info.name, sizeof info.name, "Haply Inverse3 %s%s%s", device_id.c_str(),
                grip_id.empty() ? "" : " with VerseGrip ", grip_id.c_str());
  info.joints = 3;
  info.dof = 3;
  info.buttons = grip_id.empty() ? 0 : (grip_kind == "wireless_verse_grip" ? 3 : 1);
  info.capabilities = HAPTIC_DRIVER_MEASURED_RATES;  // the service's cursor velocity
  if (!grip_id.empty()) info.capabilities |= HAPTIC_DRIVER_ORIENTATION;
  info.max_force = max_force;
  for (int i = 0; i < 3; ++i) {
    info.workspace_min[i] = centre_W[i] - workspace_radius;
    info.workspace_max[i] = centre_W[i] + workspace_radius;
    info.apparent_mass[i] = apparent_mass[i];
    info.apparent_damping[i] = apparent_damping[i];
  }
}

int Device::start() {
  if (!connection->send(probe(*this))) {  // the first state comes back for the first read
    fail("the Haply Inverse Service closed the connection");
    return HAPTIC_DRIVER_FAILED;
  }
  say(HAPTIC_DRIVER_LOG_INFO, "driving Inverse3 " + device_id + " through " + url);
  return HAPTIC_DRIVER_OK;
}

void Device::stop() {
  connection->send(probe(*this));  // a message without a force: the device idles (§3.3)
}

int Device::read(haptic_driver_reading& reading) {
  std::string text;
  // The answer to the last message (the previous tick's force, or start's probe).
  if (connection->wait_newer(seen, reply_timeout, text)) {
    if (!take(*this, text)) return HAPTIC_DRIVER_FAILED;
    ++sequence;  // a new sample; none new leaves it, and hapticd calls that stale
  } else if (!connection->connected()) {
    fail("the Haply Inverse Service closed the connection");
    return HAPTIC_DRIVER_FAILED;
  }
  for (int i = 0; i < 3; ++i) {
    reading.q[i] = position_W[i];
    reading.q_dot[i] = velocity_W[i];
  }
  std::memcpy(reading.orientation_W, orientation_W, sizeof orientation_W);
  reading.buttons = buttons;
  reading.sequence = sequence;
  return HAPTIC_DRIVER_OK;
}

int Device::write(const haptic_driver_command& command, double /*dt*/) {
  const std::uint64_t epoch = safe_epoch.load(std::memory_order_acquire);
  // W to Haply's frame: X = y_W, Y = -x_W, Z = z_W.
  const Json force = {{"x", command.tau[1]}, {"y", -command.tau[0]}, {"z", command.tau[2]}};
  Json commands = {{"set_cursor_force", {{force_key, force}}}};
  std::lock_guard lock(send_mutex);
  // The safe state came while this write was being made: its force is not to follow it (driver.h).
  // Checked before the message is made, so that a dropped write never takes the session's
  // configuration with it.
  if (safe_epoch.load(std::memory_order_relaxed) != epoch) return HAPTIC_DRIVER_OK;
  const std::string message = command_message(*this, std::move(commands));
  if (!connection->send(message)) {
    fail("the Haply Inverse Service closed the connection");
    return HAPTIC_DRIVER_FAILED;
  }
  return HAPTIC_DRIVER_OK;
}

void Device::enter_safe_state() {
  // A message without a force: commands are per message, so the device idles (§3.3) until the
  // next write.
  const std::string message = probe(*this);
  std::lock_guard lock(send_mutex);
  safe_epoch.fetch_add(1, std::memory_order_acq_rel);
  connection->send(message);
}

int Device::list_devices(const haptic::vendor::DriverParams& params, std::string& out) {
  const std::string url = params.text("url").value_or(kDefaultUrl);
  Connection connection;
  if (std::string why = connection.open(url, std::chrono::milliseconds(1000)); !why.empty()) {
    out = why + ": start the Haply Inverse Service (Haply Hub)";
    return -1;
  }
  std::string text;
  std::uint64_t seen = 0;
  if (!connection.wait_newer(seen, std::chrono::seconds(1), text)) {
    out = "the service at " + url + " sent no inventory";
    return -1;
  }
  const Json inventory = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  int found = 0;
  if (inventory.is_object() && inventory.contains("inverse3") && inventory["inverse3"].is_array()) {
    for (const Json& arm : inventory["inverse3"]) {
      const std::string id = arm.value("device_id", std::string());
      const std::string hand = member(arm, "config").value("handedness", std::string("?"));
      out += "{\"device_id\": \"" + id + "\"}\tHaply Inverse3 " + id + " (" + hand + "-handed)\n";
      ++found;
    }
  }
  return found;
}

void Device::last_error(char* error) const {
  std::lock_guard lock(failure_mutex);
  std::snprintf(error, HAPTIC_DRIVER_ERROR_SIZE, "%s", failure.c_str());
}

}  // namespace

HAPTIC_VENDOR_DRIVER(Device)
