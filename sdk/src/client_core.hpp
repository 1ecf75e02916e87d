#pragma once
// What a Client and its handles share: the gRPC stub, the session, and the UDP link. Handles keep
// a weak_ptr to it, so one that outlives its Client finds it gone and does nothing.

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptic/client.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "udp_link.hpp"

namespace haptic::detail {

/// The host part of "host:port", "[v6]:port" or a gRPC target such as "dns:///host:port" or
/// "ipv4:host:port": the UDP data plane lives on the same host as the control plane.
std::string host_of(std::string address);
/// Whether a gRPC target reaches this machine only, so a token may go in clear: a Unix socket, or
/// every address it names a loopback literal (localhost, 127.0.0.0/8, ::1, ::ffff:127.0.0.0/104;
/// haptic/io/loopback) — in a bare host:port, dns:, dns:/// or each member of an ipv4:/ipv6: list.
/// Any other name is not, whatever it resolves to, nor is another resolver's dns://authority/.
bool stays_on_this_host(const std::string& target);

/// The first kFastReconnectWindow of a loss is retried at least every kFastReconnectPeriod: a
/// server restarting (systemd's RestartSec is 2 s, and it starts in a fraction of one) is then met
/// within a tenth of a second of being ready, not after a backoff that has grown to a second.
inline constexpr std::chrono::milliseconds kFastReconnectWindow{10'000};
inline constexpr std::chrono::milliseconds kFastReconnectPeriod{100};
/// How long a lost client waits before its next try, `outage` into the loss, after waiting
/// `previous` (zero before the first): ClientConfig::reconnect_backoff_min doubling, capped at
/// kFastReconnectPeriod (or the min, if larger) through kFastReconnectWindow, then doubling on to
/// reconnect_backoff_max (a server that stays away is not asked ten times a second for ever).
std::chrono::milliseconds next_reconnect_delay(std::chrono::milliseconds previous,
                                               std::chrono::milliseconds outage, const ClientConfig& config);

class ClientCore {
 public:
  explicit ClientCore(ClientConfig config);
  ~ClientCore();

  /// Runs one unary RPC with the configured deadline (or `timeout`, when longer work is asked
  /// for); throws the mapped haptic::Error.
  template <typename Request, typename Response, typename Method>
  Response call(const char* name, Method method, Request request,
                std::optional<std::chrono::milliseconds> timeout = std::nullopt) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + timeout.value_or(config_.rpc_timeout));
    authenticate(context);
    Response response;
    throw_status(((*stub()).*method)(&context, request, &response), name);
    return response;
  }

  // Items are known by a key of the client's own, stable across reconnections (the server's id
  // changes when a restarted server is given the item again); server_id() translates.
  struct Created {
    std::uint64_t key = 0;
    v1::ItemRef ref;
  };
  Created create_object(const v1::Object& object);
  /// Replaces the object; returns the stability report of its new impedance.
  v1::ItemRef update_object(std::uint64_t key, const v1::Object& object);
  void delete_object(std::uint64_t key);
  Created create_field(const v1::Field& field);
  void update_field(std::uint64_t key, const v1::Field& field);
  void delete_field(std::uint64_t key);
  struct Applied {
    v1::ApplySceneResponse reply;
    std::vector<std::uint64_t> object_keys, field_keys;
  };
  /// Replaces the session's scene; on success bumps the scene generation, staling older handles.
  Applied apply_scene(const v1::Scene& scene);
  std::uint64_t scene_generation() const { return scene_generation_.load(); }
  /// A lockstep Reset: on success the session holds no items (handles go stale, as after
  /// apply_scene) and the state stream's ticks start again.
  void reset();
  /// A Step reply's run (StepResponse.run): if another client reset the server since, the ticks
  /// this client knew are forgotten before the reply's sample is offered.
  void note_run(std::uint64_t run);
  /// The item's id on the server now; 0 if the client no longer holds it.
  std::uint64_t server_id(std::uint64_t key) const;
  /// Sets the state decimation; for n > 0 waits until the server knows our UDP address.
  void subscribe(std::uint32_t decimation);
  /// Whether the calling thread runs one of this client's callbacks (state, events, connection).
  bool on_callback_thread() const;
  void close_session();
  /// Streams WatchEvents on a thread of its own and calls `callback` with each event (the first
  /// is WATCH_STARTED); a new callback replaces the stream, an empty one ends it. Resumed after a
  /// reconnection.
  void watch_events(std::function<void(const v1::Event&)> callback);

  /// Attaches an observer (Client::observe): every accepted State from the UDP link, its own
  /// event stream if `events` (opened first; throws the refusal), every connection change.
  /// Returns its id for unobserve.
  std::uint64_t observe(std::shared_ptr<ReceiveObserver> observer, bool events);
  /// Detaches it, waiting out a call in progress; unknown ids are ignored.
  void unobserve(std::uint64_t id) noexcept;

  /// Called on the supervisor's thread with each change of the connection.
  void on_connection(std::function<void(const ConnectionChange&)> callback);
  ConnectionChange::State connection_state() const { return connection_state_.load(); }
  /// Heartbeats off: the client plays a vanished one, and the supervisor looks away meanwhile.
  void set_heartbeats_enabled(bool enabled);
  ReceiveCounters counters() const;

  std::uint64_t session_id() const { return session_id_.load(); }
  const DeviceInfo& device_info() const { return device_info_; }
  std::chrono::milliseconds lease_timeout() const { return lease_timeout_; }
  const ClientConfig& config() const { return config_; }
  UdpLink& udp() { return *udp_; }

 private:
  static void throw_status(const grpc::Status& status, const char* name);
  std::shared_ptr<v1::Haptic::Stub> stub() const {
    std::lock_guard lock(identity_mutex_);
    return stub_;
  }
  /// Adds what every call carries: the bearer token (if any) and the session secret (once open).
  void authenticate(grpc::ClientContext& context) const;
  v1::OpenSessionResponse open_session();
  /// open_session() for the first connection: a ConnectionError that a TLS mismatch explains
  /// says which setting to change (tls_diagnosis).
  v1::OpenSessionResponse open_session_saying_why();
  /// Where datagrams go: ClientConfig::udp_address if given, else the server's host and the port
  /// OpenSession named.
  std::string udp_host() const;
  std::uint16_t udp_port(const v1::OpenSessionResponse& opened) const;
  /// CreateObject (object given) or CreateField (field given) in the current session.
  v1::ItemRef send_create(const v1::Object* object, const v1::Field* field);
  /// Keeps `key` under the server's `id` with the message that made it.
  std::uint64_t remember(std::uint64_t id, const v1::Object* object, const v1::Field* field);
  /// The item's server id, or NotFoundError naming `call` (an item a reconnection could not
  /// register again says why).
  std::uint64_t require_server_id(std::uint64_t key, const char* call) const;

  // Connection supervision (a thread of its own): a quiet connection is probed; a failed probe is
  // a loss, recovered with backoff: the same session if it still exists, else a new one with the
  // items registered again, the state stream and the event watch resumed.
  enum class Probe { kAlive, kUnreachable, kSessionGone, kEnded };
  void supervise();
  Probe probe(std::string& why);
  /// False when the session was ended for good (announced): supervision stops.
  bool recover(std::string why);
  /// Opens a new session and gives it everything the old one held. Throws if the opening fails.
  void reopen();
  void announce(ConnectionChange change);
  void stop_supervisor();
  /// Waits `duration` unless the supervisor is told to stop; false when it is.
  bool supervisor_wait(std::chrono::milliseconds duration);

  ClientConfig config_;
  std::shared_ptr<v1::Haptic::Stub> stub_;  // guarded by identity_mutex_: renewed on a loss
  std::atomic<std::uint64_t> session_id_{0};
  mutable std::mutex identity_mutex_;
  std::string session_secret_;  // guarded by identity_mutex_; OpenSession's, empty until then
  bool closed_ = false;
  DeviceInfo device_info_;
  std::chrono::milliseconds lease_timeout_{0};
  std::atomic<std::uint64_t> scene_generation_{0};
  // The server's run as last seen (0: never reset; a client that joins later forgets its first
  // samples once, harmlessly, at its first step). Guarded by run_mutex_.
  std::uint64_t known_run_ = 0;
  std::mutex run_mutex_;
  std::atomic<std::uint32_t> decimation_{0};  // the state stream asked for, resumed after a loss
  std::unique_ptr<UdpLink> udp_;

  struct Item {
    bool is_object = true;
    v1::Object object;
    v1::Field field;
    std::uint64_t server_id = 0;  // 0: a reconnection could not register it again
    std::string lost_reason;
  };
  mutable std::mutex items_mutex_;
  std::map<std::uint64_t, Item> items_;  // by key, so in the order they were made
  std::uint64_t next_key_ = 1;           // guarded by items_mutex_

  // The event stream: its thread, its context (cancelled from here to end it), its callback.
  mutable std::mutex events_mutex_;
  std::unique_ptr<grpc::ClientContext> events_context_;
  std::function<void(const v1::Event&)> events_callback_;  // guarded by events_mutex_
  std::thread events_thread_;
  void stop_events();
  // A WatchEvents stream: its context (cancelled to end it) and the thread that reads it.
  struct Watch {
    std::unique_ptr<grpc::ClientContext> context;
    std::thread thread;
  };
  /// Opens a stream for this session and runs `callback` on its own thread with each event,
  /// WATCH_STARTED first; throws the server's refusal (read before this returns).
  Watch open_watch(std::function<void(const v1::Event&)> callback);
  /// Cancels the stream and joins its thread.
  static void end_watch(Watch& watch);

  // Observers (Client::observe), by id. observers_mutex_ is held while one is called with a
  // connection change and while an event stream of theirs is reopened; never by the receive path
  // (the UdpLink keeps its own list of sample taps).
  struct Observer {
    std::shared_ptr<ReceiveObserver> observer;
    bool events = false;
    Watch watch;
  };
  std::mutex observers_mutex_;
  std::map<std::uint64_t, Observer> observers_;  // guarded by observers_mutex_
  std::uint64_t next_observer_id_ = 1;           // guarded by observers_mutex_
  /// Reopens the observers' event streams in a new session (reopen).
  void resume_observer_watches();
  void end_observer_watches();

  std::mutex connection_mutex_;
  std::function<void(const ConnectionChange&)> connection_callback_;  // guarded by connection_mutex_
  std::atomic<ConnectionChange::State> connection_state_{ConnectionChange::State::kConnected};
  std::atomic<bool> heartbeats_enabled_{true};
  std::atomic<std::uint64_t> reconnects_{0};
  std::mutex supervisor_mutex_;
  std::condition_variable supervisor_wake_;
  bool supervisor_stop_ = false;  // guarded by supervisor_mutex_
  std::thread supervisor_;
};

}  // namespace haptic::detail
