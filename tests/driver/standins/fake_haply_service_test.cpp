// The stand-in Haply Inverse Service (fake_haply_service.hpp) tested on its own, the way a driver
// uses it: a websocketpp client on ws://127.0.0.1:PORT (the simulation channel) and a second one
// on ws://127.0.0.1:PORT/control (the tests' control channel). Each test starts its own service on
// port 0 in-process; the last one starts the fake-haply-service executable. Every wait is bounded.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "fake_haply_service.hpp"

extern char** environ;

namespace {

using json = nlohmann::json;
using namespace std::chrono_literals;
using WsClient = websocketpp::client<websocketpp::config::asio_client>;

constexpr auto kWait = 2s;  // the bound on every expected reply

// A WebSocket client on a thread of its own, with a queue of the text messages received.
class Client {
 public:
  Client() {
    ws_.clear_access_channels(websocketpp::log::alevel::all);
    ws_.clear_error_channels(websocketpp::log::elevel::all);
    ws_.init_asio();
    ws_.start_perpetual();
    ws_.set_socket_init_handler([](websocketpp::connection_hdl, asio::ip::tcp::socket& s) {
      asio::error_code ec;
      s.set_option(asio::ip::tcp::no_delay(true), ec);
    });
    ws_.set_open_handler([this](websocketpp::connection_hdl) { set(&open_); });
    ws_.set_close_handler([this](websocketpp::connection_hdl hdl) {
      auto con = ws_.get_con_from_hdl(hdl);
      std::lock_guard<std::mutex> lock(mu_);
      close_code_ = con->get_remote_close_code();
      closed_ = true;
      cv_.notify_all();
    });
    ws_.set_fail_handler([this](websocketpp::connection_hdl) { set(&closed_); });
    ws_.set_message_handler([this](websocketpp::connection_hdl, WsClient::message_ptr msg) {
      std::lock_guard<std::mutex> lock(mu_);
      messages_.push_back(msg->get_payload());
      cv_.notify_all();
    });
    thread_ = std::thread([this] { ws_.run(); });
  }

  ~Client() {
    bool was_open;
    {
      std::lock_guard<std::mutex> lock(mu_);
      was_open = open_ && !closed_;
    }
    if (was_open) {
      asio::post(ws_.get_io_service(), [this] {
        websocketpp::lib::error_code ec;
        ws_.close(hdl_, websocketpp::close::status::normal, "", ec);
      });
      wait_closed(1s);
    }
    ws_.stop_perpetual();
    ws_.stop();
    thread_.join();
  }

  bool connect(const std::string& uri) {
    websocketpp::lib::error_code ec;
    auto con = ws_.get_connection(uri, ec);
    if (ec) return false;
    hdl_ = con->get_handle();
    ws_.connect(con);
    std::unique_lock<std::mutex> lock(mu_);
    return cv_.wait_for(lock, kWait, [this] { return open_ || closed_; }) && open_ && !closed_;
  }

  void send(const std::string& text) {
    asio::post(ws_.get_io_service(), [this, text] {
      websocketpp::lib::error_code ec;
      ws_.send(hdl_, text, websocketpp::frame::opcode::text, ec);
    });
  }

  std::optional<std::string> next(std::chrono::milliseconds timeout = kWait) {
    std::unique_lock<std::mutex> lock(mu_);
    if (!cv_.wait_for(lock, timeout, [this] { return !messages_.empty(); })) return std::nullopt;
    std::string m = std::move(messages_.front());
    messages_.pop_front();
    return m;
  }

  // The reply to `text` as JSON (null with a failure if none came in time).
  json request(const std::string& text) {
    send(text);
    auto reply = next();
    if (!reply) {
      ADD_FAILURE() << "no reply to " << text;
      return json();
    }
    return json::parse(*reply, nullptr, false);
  }

  std::string command(const std::string& text) {
    send(text);
    auto reply = next();
    if (!reply) {
      ADD_FAILURE() << "no reply to control command " << text;
      return {};
    }
    return *reply;
  }

  bool wait_closed(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mu_);
    return cv_.wait_for(lock, timeout, [this] { return closed_; });
  }

  int close_code() {
    std::lock_guard<std::mutex> lock(mu_);
    return close_code_;
  }

 private:
  void set(bool* flag) {
    std::lock_guard<std::mutex> lock(mu_);
    *flag = true;
    cv_.notify_all();
  }

  WsClient ws_;
  std::thread thread_;
  websocketpp::connection_hdl hdl_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::string> messages_;
  bool open_ = false, closed_ = false;
  int close_code_ = 0;
};

// One service, the simulation client (its inventory already taken) and the control client.
struct Rig {
  explicit Rig(const std::string& devices = fake_haply::kDefaultDevices) {
    fake_haply::Options opt;
    opt.port = 0;
    opt.devices = devices;
    service = std::make_unique<fake_haply::Service>(opt);
    std::string error;
    if (!service->start(&error)) {
      ADD_FAILURE() << "start: " << error;
      return;
    }
    base = "ws://127.0.0.1:" + std::to_string(service->port());
    EXPECT_TRUE(control.connect(base + "/control"));
    EXPECT_TRUE(sim.connect(base));
    auto first = sim.next();
    EXPECT_TRUE(first.has_value());
    if (first) inventory = json::parse(*first, nullptr, false);
  }

  std::unique_ptr<fake_haply::Service> service;
  std::string base;
  Client control, sim;
  json inventory;
};

std::string force_message(const char* key, double fx, double fy, double fz) {
  json m{{"inverse3",
          json::array({{{"device_id", "049D"},
                        {"commands", {{"set_cursor_force", {{key, {{"x", fx}, {"y", fy}, {"z", fz}}}}}}}}})}};
  return m.dump();
}

const std::string kProbe =
    R"({"inverse3": [{"device_id": "049D", "commands": {"probe_position": {}}}]})";

// The mass-damper's displacement from rest under a constant force f for time t.
double predicted_displacement(double f, double t) {
  const double tau = fake_haply::kMass / fake_haply::kDamping;
  return f / fake_haply::kDamping * (t - tau * (1 - std::exp(-t / tau)));
}

const json& arm(const json& message) { return message["inverse3"][0]; }

double cursor(const json& message, const char* axis) {
  return arm(message)["state"]["cursor_position"][axis].get<double>();
}

TEST(FakeHaplyService, SendsTheInventoryOnConnect) {
  Rig rig;
  const json& inv = rig.inventory;
  ASSERT_TRUE(inv.is_object()) << inv;
  EXPECT_TRUE(inv["session_id"].is_number_integer());
  ASSERT_EQ(inv["inverse3"].size(), 1u);
  const json& a = inv["inverse3"][0];
  EXPECT_EQ(a["device_id"], "049D");
  EXPECT_EQ(a["config"]["handedness"], "right");
  EXPECT_EQ(a["config"]["device_info"]["id"], "049D");
  EXPECT_EQ(a["config"]["device_info"]["device_type"], 4);
  EXPECT_DOUBLE_EQ(a["state"]["cursor_position"]["x"].get<double>(), fake_haply::kRestX);
  EXPECT_DOUBLE_EQ(a["state"]["cursor_position"]["y"].get<double>(), fake_haply::kRestY);
  EXPECT_DOUBLE_EQ(a["state"]["cursor_position"]["z"].get<double>(), fake_haply::kRestZ);
  EXPECT_EQ(a["state"]["cursor_velocity"], (json{{"x", 0.0}, {"y", 0.0}, {"z", 0.0}}));
  EXPECT_EQ(a["status"]["calibrated"], true);
  EXPECT_EQ(a["status"]["ready"], true);
  ASSERT_EQ(inv["wireless_verse_grip"].size(), 1u);
  const json& g = inv["wireless_verse_grip"][0];
  EXPECT_EQ(g["device_id"], "0");
  EXPECT_EQ(g["state"]["orientation"], (json{{"w", 1.0}, {"x", 0.0}, {"y", 0.0}, {"z", 0.0}}));
  EXPECT_EQ(g["state"]["buttons"], (json{{"a", false}, {"b", false}, {"c", false}}));
  EXPECT_DOUBLE_EQ(g["state"]["battery_level"].get<double>(), 0.9);
  EXPECT_TRUE(inv["verse_grip"].is_array() && inv["verse_grip"].empty());
  // A second client gets its own session.
  Client other;
  ASSERT_TRUE(other.connect(rig.base));
  auto second = other.next();
  ASSERT_TRUE(second);
  EXPECT_NE(json::parse(*second)["session_id"], inv["session_id"]);
}

TEST(FakeHaplyService, AnswersExactlyOnceForEachMessage) {
  Rig rig;
  for (int i = 0; i < 20; ++i) rig.sim.send(kProbe);
  for (int i = 0; i < 20; ++i) {
    auto reply = rig.sim.next();
    ASSERT_TRUE(reply) << "reply " << i;
    const json m = json::parse(*reply);
    EXPECT_TRUE(m["inverse3"][0].contains("state"));
    EXPECT_TRUE(m["inverse3"][0].contains("status"));
    EXPECT_FALSE(m["inverse3"][0].contains("config"));  // §3.2: later updates: state and status
    EXPECT_FALSE(m.contains("error")) << m;
  }
  EXPECT_FALSE(rig.sim.next(200ms)) << "a 21st reply to 20 messages";
  EXPECT_EQ(rig.control.command("calls"), "connect\ninverse3 049D probe_position x20\n");
}

void expect_force_moves_cursor(const char* key) {
  Rig rig;
  rig.control.command("clear");
  json last;
  for (int i = 0; i < 100; ++i) last = rig.sim.request(force_message(key, 1, 0, 0));
  const double want = predicted_displacement(1.0, 100 * fake_haply::kDefaultDt);
  EXPECT_NEAR(cursor(last, "x") - fake_haply::kRestX, want, 0.01 * want);
  EXPECT_DOUBLE_EQ(cursor(last, "y"), fake_haply::kRestY);
  EXPECT_DOUBLE_EQ(cursor(last, "z"), fake_haply::kRestZ);
  EXPECT_DOUBLE_EQ(arm(last)["state"]["current_cursor_force"]["x"].get<double>(), 1.0);
  EXPECT_EQ(arm(last)["state"]["control_mode"], "force");
  EXPECT_EQ(rig.control.command("calls"), "inverse3 049D set_cursor_force 1 0 0 x100\n");
}

TEST(FakeHaplyService, VectorForceMovesTheCursorAsTheMassDamperPredicts) {
  expect_force_moves_cursor("vector");
}

TEST(FakeHaplyService, ValuesForceMovesTheCursorTheSameWay) { expect_force_moves_cursor("values"); }

TEST(FakeHaplyService, ForcesArePerTick) {
  Rig rig;
  // No command: nothing moves.
  json m;
  for (int i = 0; i < 50; ++i) m = rig.sim.request(kProbe);
  EXPECT_DOUBLE_EQ(cursor(m, "x"), fake_haply::kRestX);
  EXPECT_EQ(arm(m)["state"]["control_mode"], "idle");
  // One forced message, then probes: the velocity only decays (no force carried over).
  m = rig.sim.request(force_message("vector", 1, 0, 0));
  double v = arm(m)["state"]["cursor_velocity"]["x"].get<double>();
  ASSERT_GT(v, 0);
  const double decay = std::exp(-fake_haply::kDefaultDt * fake_haply::kDamping / fake_haply::kMass);
  for (int i = 0; i < 10; ++i) {
    m = rig.sim.request(kProbe);
    const double v2 = arm(m)["state"]["cursor_velocity"]["x"].get<double>();
    EXPECT_NEAR(v2, v * decay, 1e-12);
    EXPECT_DOUBLE_EQ(arm(m)["state"]["current_cursor_force"]["x"].get<double>(), 0.0);
    v = v2;
  }
  // Forces within one message add up (§3.3); above 10 N the magnitude is clamped.
  m = rig.sim.request(
      R"({"inverse3": [{"device_id": "049D", "commands": {"set_cursor_force": {"vector": {"x": 30, "y": 0, "z": 0}}}},)"
      R"( {"device_id": "049D", "commands": {"set_cursor_force": {"vector": {"x": 0, "y": 40, "z": 0}}}}]})");
  EXPECT_NEAR(arm(m)["state"]["current_cursor_force"]["x"].get<double>(), 6.0, 1e-12);
  EXPECT_NEAR(arm(m)["state"]["current_cursor_force"]["y"].get<double>(), 8.0, 1e-12);
}

TEST(FakeHaplyService, ControlChannelHandButtonsAndOrientationAppearInTheState) {
  Rig rig;
  EXPECT_EQ(rig.control.command("hand 049D 0 0 -1"), "ok");
  EXPECT_EQ(rig.control.command("button 0 b 1"), "ok");
  EXPECT_EQ(rig.control.command("orientation 0 1 0 0 1"), "ok");
  json m;
  for (int i = 0; i < 100; ++i) m = rig.sim.request(kProbe);
  const double want = predicted_displacement(-1.0, 100 * fake_haply::kDefaultDt);
  EXPECT_NEAR(cursor(m, "z") - fake_haply::kRestZ, want, 0.01 * std::abs(want));
  EXPECT_DOUBLE_EQ(arm(m)["state"]["current_cursor_force"]["z"].get<double>(), 0.0);
  const json& g = m["wireless_verse_grip"][0]["state"];
  EXPECT_EQ(g["buttons"], (json{{"a", false}, {"b", true}, {"c", false}}));
  EXPECT_NEAR(g["orientation"]["w"].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(g["orientation"]["z"].get<double>(), std::sqrt(0.5), 1e-12);
  EXPECT_EQ(rig.control.command("button 0 b 0"), "ok");
  m = rig.sim.request(kProbe);
  EXPECT_EQ(m["wireless_verse_grip"][0]["state"]["buttons"]["b"], false);
  // Refusals keep the channel.
  EXPECT_EQ(rig.control.command("hand 0 1 2 3").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control.command("button 049D a 1").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control.command("fly away").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control.command("clients"), "1");
}

TEST(FakeHaplyService, WiredGripReportsOneButton) {
  Rig rig("inverse3:04BA,verse_grip:61548");
  ASSERT_EQ(rig.inventory["verse_grip"].size(), 1u);
  EXPECT_EQ(rig.inventory["verse_grip"][0]["config"]["type"], "verse_grip");
  EXPECT_EQ(rig.control.command("button 61548 a 1"), "ok");
  json m = rig.sim.request(
      R"({"verse_grip": [{"device_id": "61548", "commands": {"probe_orientation": {}}}]})");
  EXPECT_EQ(m["verse_grip"][0]["state"]["button"], true);
  EXPECT_TRUE(m["wireless_verse_grip"].empty());
  EXPECT_FALSE(m.contains("error")) << m;
}

TEST(FakeHaplyService, UnplugAndReplug) {
  Rig rig;
  EXPECT_EQ(rig.control.command("unplug 049D"), "ok");
  json m = rig.sim.request(kProbe);
  EXPECT_TRUE(m["inverse3"].is_array() && m["inverse3"].empty()) << m;
  ASSERT_TRUE(m.contains("error"));
  EXPECT_NE(m["error"].get<std::string>().find("049D"), std::string::npos);
  EXPECT_EQ(m["wireless_verse_grip"].size(), 1u);
  EXPECT_EQ(rig.control.command("replug 049D"), "ok");
  m = rig.sim.request(kProbe);
  ASSERT_EQ(m["inverse3"].size(), 1u);
  EXPECT_EQ(arm(m)["device_id"], "049D");
  EXPECT_FALSE(m.contains("error"));
  EXPECT_EQ(rig.control.command("unplug nosuch").rfind("error:", 0), 0u);
}

TEST(FakeHaplyService, StallHoldsRepliesUntilResume) {
  Rig rig;
  EXPECT_EQ(rig.control.command("stall"), "ok");
  rig.sim.send(force_message("vector", 1, 0, 0));
  rig.sim.send(kProbe);
  EXPECT_FALSE(rig.sim.next(300ms)) << "answered while stalled";
  EXPECT_EQ(rig.control.command("resume"), "ok");
  auto first = rig.sim.next();
  auto second = rig.sim.next();
  ASSERT_TRUE(first && second);
  EXPECT_DOUBLE_EQ(arm(json::parse(*first))["state"]["current_cursor_force"]["x"].get<double>(), 1);
  EXPECT_DOUBLE_EQ(arm(json::parse(*second))["state"]["current_cursor_force"]["x"].get<double>(),
                   0);
  EXPECT_FALSE(rig.sim.next(100ms));
}

TEST(FakeHaplyService, ErrorsAreAnsweredAndTheConnectionKept) {
  Rig rig;
  json m = rig.sim.request("{not json");
  ASSERT_TRUE(m.is_object());
  ASSERT_TRUE(m.contains("error"));
  EXPECT_NE(m["error"].get<std::string>().find("malformed"), std::string::npos);
  EXPECT_FALSE(m.contains("inverse3"));
  m = rig.sim.request("[1, 2]");
  EXPECT_TRUE(m.contains("error"));
  // An unknown command: the state, with an error naming it.
  m = rig.sim.request(R"({"inverse3": [{"device_id": "049D", "commands": {"warp": {}}}]})");
  ASSERT_TRUE(m.contains("error"));
  EXPECT_NE(m["error"].get<std::string>().find("warp"), std::string::npos);
  EXPECT_EQ(m["inverse3"].size(), 1u);
  // set_cursor_position is refused with an error field.
  m = rig.sim.request(
      R"({"inverse3": [{"device_id": "049D", "commands": {"set_cursor_position": {"position": {"x": 0, "y": -0.12, "z": 0.15}}}}]})");
  ASSERT_TRUE(m.contains("error"));
  EXPECT_NE(m["error"].get<std::string>().find("set_cursor_position"), std::string::npos);
  // A force without x, y, z.
  m = rig.sim.request(
      R"({"inverse3": [{"device_id": "049D", "commands": {"set_cursor_force": {"vector": {"x": 1}}}}]})");
  EXPECT_TRUE(m.contains("error"));
  // Still serving.
  m = rig.sim.request(force_message("vector", 0.5, 0, 0));
  EXPECT_FALSE(m.contains("error"));
  EXPECT_DOUBLE_EQ(arm(m)["state"]["current_cursor_force"]["x"].get<double>(), 0.5);
}

TEST(FakeHaplyService, SessionConfigureIsRecordedAndFullStateOnRequest) {
  Rig rig;
  json m = rig.sim.request(
      R"({"session": {"configure": {"profile": {"name": "hapticd-test"}}},)"
      R"( "inverse3": [{"device_id": "049D", "commands": {"set_cursor_force": {"vector": {"x": 0, "y": 0, "z": 0}}}}]})");
  EXPECT_FALSE(m.contains("error")) << m;
  EXPECT_FALSE(arm(m).contains("config"));
  m = rig.sim.request(R"({"session": {"force_render_full_state": {}}})");
  EXPECT_EQ(arm(m)["config"]["handedness"], "right");
  const std::string calls = rig.control.command("calls");
  EXPECT_NE(calls.find("session.configure profile=hapticd-test; inverse3 049D set_cursor_force 0 0 0"),
            std::string::npos)
      << calls;
  EXPECT_NE(calls.find("session.force_render_full_state"), std::string::npos) << calls;
}

TEST(FakeHaplyService, CloseEndsEveryClientsConnection) {
  Rig rig;
  EXPECT_EQ(rig.control.command("close"), "ok");
  EXPECT_TRUE(rig.sim.wait_closed(kWait));
  EXPECT_EQ(rig.sim.close_code(), 1001);
  EXPECT_EQ(rig.control.command("clients"), "0");  // the control channel stays
  Client again;  // and new clients are served
  ASSERT_TRUE(again.connect(rig.base));
  EXPECT_TRUE(again.next());
}

TEST(FakeHaplyService, StopClosesClients) {
  Rig rig;
  const auto t0 = std::chrono::steady_clock::now();
  rig.service->stop();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 3s);
  EXPECT_TRUE(rig.sim.wait_closed(kWait));
  Client late;
  EXPECT_FALSE(late.connect(rig.base));
}

TEST(FakeHaplyService, RefusesABadDeviceListAndUnknownPaths) {
  fake_haply::Options opt;
  opt.port = 0;
  opt.devices = "inverse3:049D,falcon:1";
  fake_haply::Service bad(opt);
  std::string error;
  EXPECT_FALSE(bad.start(&error));
  EXPECT_NE(error.find("falcon"), std::string::npos);
  Rig rig;
  Client stray;
  EXPECT_FALSE(stray.connect(rig.base + "/elsewhere"));
  EXPECT_EQ(rig.service->control("clients"), "1");  // in-process control
}

// The executable: port 0, "port N" on stdout, served, SIGTERM ends it with status 0.
TEST(FakeHaplyService, ExecutableServesUntilSigterm) {
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  posix_spawn_file_actions_addclose(&actions, out[0]);
  std::string exe = FAKE_HAPLY_SERVICE_EXECUTABLE;
  char* argv[] = {exe.data(), const_cast<char*>("--port"), const_cast<char*>("0"),
                  const_cast<char*>("--devices"), const_cast<char*>("inverse3:04BA"),
                  const_cast<char*>("--dt"), const_cast<char*>("0.002"), nullptr};
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv, environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  close(out[1]);

  std::string text;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (text.find('\n') == std::string::npos && std::chrono::steady_clock::now() < deadline) {
    pollfd p{out[0], POLLIN, 0};
    if (poll(&p, 1, 100) > 0) {
      char buf[64];
      const ssize_t n = read(out[0], buf, sizeof buf);
      if (n <= 0) break;
      text.append(buf, static_cast<std::size_t>(n));
    }
  }
  close(out[0]);
  int port = 0;
  EXPECT_EQ(std::sscanf(text.c_str(), "port %d", &port), 1) << text;
  if (port > 0) {
    Client c;
    ASSERT_TRUE(c.connect("ws://127.0.0.1:" + std::to_string(port)));
    auto inv = c.next();
    ASSERT_TRUE(inv);
    EXPECT_EQ(json::parse(*inv)["inverse3"][0]["device_id"], "04BA");
    const json m = c.request(force_message("vector", 0, 0, 0).replace(
        force_message("vector", 0, 0, 0).find("049D"), 4, "04BA"));
    EXPECT_FALSE(m.contains("error")) << m;
    kill(pid, SIGTERM);
    EXPECT_TRUE(c.wait_closed(kWait));
  } else {
    kill(pid, SIGTERM);
  }
  int status = -1;
  pid_t done = 0;
  const auto exit_deadline = std::chrono::steady_clock::now() + 5s;
  while ((done = waitpid(pid, &status, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() < exit_deadline)
    std::this_thread::sleep_for(10ms);
  if (done == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    FAIL() << "fake-haply-service did not exit within 5 s of SIGTERM";
  }
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
}

}  // namespace
