// The stand-in Haply Inverse Service (fake_haply_service.cpp): a WebSocket server that speaks the
// simulation channel's JSON protocol over a simulated plant, so that a driver for the Haply
// Inverse3 and its VerseGrip can run in ctest without Haply's software. Every protocol fact used
// is written from driver/vendors/SOURCES.md section 3, and the comment beside it names the section
// (and through it the original source). No Haply code or SDK is used.
//
// This header pulls in neither websocketpp nor Asio, so a C++20 test can link the static library
// `fake_haply_service` and run the service in-process; the library itself is built as C++17
// (websocketpp 0.8.2 does not compile as C++20).
#pragma once

#include <memory>
#include <string>

namespace fake_haply {

// ---- Protocol facts (SOURCES.md §3) ----
inline constexpr int kDefaultPort = 10001;  // §3.1 [HAPLY-svc]: simulation channel, WebSocket
// Device ids as in §3.2's examples: Inverse3 "049D" (3.5.x inventory), wireless grip "0" (3.4.x
// HTTP /devices example).
inline constexpr const char* kDefaultDevices = "inverse3:049D,wireless_verse_grip:0";
inline constexpr int kInverse3DeviceType = 4;  // §3.2: config.device_info.device_type 4 (3.5.x)
// §3.4: the 3.4.x inventory example reports cursor_position ≈ (0.078, -0.148, 0.143) m at rest.
inline constexpr double kRestX = 0.078, kRestY = -0.148, kRestZ = 0.143;

// ---- The plant: the stand-in's own figures (§3.4: no workspace or max-force figure found) ----
inline constexpr double kDefaultDt = 0.001;  // s, one step per received message
inline constexpr double kMass = 0.2;         // kg, the cursor's point mass
inline constexpr double kDamping = 1.0;      // N·s/m per axis
inline constexpr double kMaxForce = 10.0;    // N, the commanded force's magnitude is clamped here
inline constexpr double kBatteryLevel = 0.9;  // wireless grip's state.battery_level at start

struct Options {
  std::string address = "127.0.0.1";
  int port = kDefaultPort;  // 0: any free port (Service::port() tells which)
  std::string devices = kDefaultDevices;  // "inverse3:ID,verse_grip:ID,wireless_verse_grip:ID"
  double dt = kDefaultDt;
};

// The service: start() listens and serves on a thread of its own until stop() (or destruction).
class Service {
 public:
  explicit Service(Options options = {});
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Parses the device list, listens and starts serving. false with *error set on failure.
  bool start(std::string* error = nullptr);
  int port() const;  // the port listened on (after start)
  // Runs one control-channel command (the same as a text message on ws://.../control) on the
  // service's thread and returns its answer: "ok", "error: ...", or the command's text.
  std::string control(const std::string& command);
  // Closes every connection (going away) and stops serving; waits at most about 1 s for clients.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fake_haply
