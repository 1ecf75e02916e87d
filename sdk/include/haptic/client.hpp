#pragma once
// haptic::Client: one session with a hapticd server. Objects and fields are registered through
// RAII handles; state arrives by callback or by polling.
//
//   haptic::Client client(haptic::ClientConfig{.server_address = "host:50051"});
//   haptic::ObjectHandle wall = client.add_wall({.normal = {0, 0, 1}, .impedance = {1000, 1}});
//   haptic::State state;
//   client.poll_state(state, std::chrono::milliseconds(100));

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "haptic/error.hpp"
#include "haptic/types.hpp"

namespace haptic {

namespace detail {
class ClientCore;
struct WireObject;  // an object converted for the wire (sdk/src/conversions.hpp)
struct WireField;
struct WireScene;
}

/// The API version this SDK speaks (haptic.v1.API_VERSION_CURRENT).
inline constexpr std::uint32_t kApiVersion = 5;

/// TLS for the control plane (the server's security.tls; docs/deployment.md). The UDP session
/// key then reaches the client encrypted.
struct TlsOptions {
  std::string ca_file;      ///< PEM: the CA that signed the server's certificate. Required.
  std::string cert_file;    ///< PEM: this client's certificate, for a server asking for one (mTLS).
  std::string key_file;     ///< PEM: its private key; with cert_file.
  /// The name the server's certificate must carry; default: the host of server_address.
  std::string server_name;
};

struct ClientConfig {
  std::string server_address = "127.0.0.1:50051";  ///< gRPC host:port of hapticd.
  /// Present: TLS (needed when the server has security.tls). Absent: plaintext.
  std::optional<TlsOptions> tls;
  /// The bearer token the server gave this client (its security.tokens); sent with every call.
  /// Empty: none (a server without tokens). Sent only over TLS or to a loopback address
  /// (localhost, a numeric 127.x.y.z, ::1 or ::ffff:127.x.y.z, a unix: target; any other name,
  /// and a gRPC address list, count as another host): with a token, no `tls` and another host,
  /// the Client refuses to start (InvalidArgumentError naming TlsOptions), since anyone on the
  /// network could read the token and act with its role.
  std::string token;
  /// Sends `token` in clear to a non-loopback address all the same, for a lab that has chosen
  /// that on a network it trusts; said on stderr each time a Client starts so.
  bool allow_plaintext_token = false;
  std::string client_name = "haptic-client";       ///< 1..64 printable characters; shown in logs.
  std::chrono::milliseconds rpc_timeout{2000};     ///< Deadline of every control-plane call.
  std::chrono::milliseconds heartbeat_period{100}; ///< UDP heartbeat period; keep well under the lease.
  std::uint32_t state_decimation = 1;              ///< State every n-th tick; 0: no state stream.
  /// Lockstep flow control: the client acknowledges what it has read (with heartbeats, one per
  /// quarter of what its socket holds), and a lockstep server never has more unacknowledged than
  /// that, so a Step of any length reaches it whole (the Step waits for slow readers; one that
  /// reads nothing for a second is sent on without waiting, its losses counted). false: every due
  /// State is sent at once, and what the socket cannot hold is lost and counted
  /// (ReceiveCounters::lost). Real-time servers never wait on a client either way.
  bool lockstep_flow_control = true;
  /// "host:port" to send datagrams to instead of server_address's host and the UDP port the
  /// server names: a port forward or a relay between client and server. Empty: the server's.
  /// (The server still answers the address the datagrams arrive from.)
  std::string udp_address;
  /// The server's device port this client uses (its device info, simulated operator, state):
  /// 0 is the configured device, 1.. the server's extra_devices (several users, one scene).
  std::uint32_t device_index = 0;
  /// Reconnect on its own when the server stops answering or forgets the session (a restart):
  /// probes a quiet connection every lease_timeout / 4 (at most 500 ms), retries after
  /// reconnect_backoff_min, doubling to at most 100 ms for the first 10 s of a loss (a restarting
  /// server is met within a tenth of a second of being ready), then on to reconnect_backoff_max.
  /// Client::on_connection tells.
  bool reconnect = true;
  std::chrono::milliseconds reconnect_backoff_min{50};
  std::chrono::milliseconds reconnect_backoff_max{1000};
};

namespace detail {

/// What ObjectHandle and FieldHandle share: a weak reference to the client's internals, the
/// item's id and the scene generation it was made in. Move-only; removes the item when destroyed
/// (errors are swallowed there: call remove() to see them). Harmless if it outlives its Client.
class ItemHandle {
 public:
  ItemHandle(ItemHandle&& other) noexcept;
  ItemHandle& operator=(ItemHandle&& other) noexcept;
  ItemHandle(const ItemHandle&) = delete;
  ItemHandle& operator=(const ItemHandle&) = delete;
  ~ItemHandle();

  /// The item's id on the server now (a reconnection that registered it again changes it), or
  /// the last one known if the Client is gone; 0 when the handle owns nothing.
  std::uint64_t id() const noexcept;
  /// True while this handle will remove the item.
  bool owned() const noexcept { return key_ != 0; }
  /// Removes the item now; its force ramps out on the server. Throws haptic::Error. Does
  /// nothing if the handle owns nothing, its Client is gone, or Client::apply_scene replaced it.
  void remove();
  /// Stops owning the item (it stays until the session ends); returns its id.
  std::uint64_t release() noexcept;

 protected:
  enum class Kind { kObject, kField };
  explicit ItemHandle(Kind kind) : kind_(kind) {}
  ItemHandle(Kind kind, std::weak_ptr<ClientCore> core, std::uint64_t key, std::uint64_t id,
             std::uint64_t generation);
  /// The client, if it still exists and the item is still in its scene; else throws (`call`
  /// names the operation in the error).
  ClientCore& current(const char* call) const;
  std::uint64_t key() const noexcept { return key_; }

 private:
  void drop() noexcept;  // removes the item if owned, swallowing errors
  Kind kind_;
  std::weak_ptr<ClientCore> core_;
  std::uint64_t key_ = 0;         // the client's own name for the item (ClientCore), 0: none
  std::uint64_t id_ = 0;          // its server id when last looked up
  std::uint64_t generation_ = 0;  // the client's scene generation when the item was made
};

}  // namespace detail

/// A registered object of any kind; see detail::ItemHandle for ownership.
class ObjectHandle : public detail::ItemHandle {
 public:
  ObjectHandle() : ItemHandle(Kind::kObject) {}
  /// Replaces the object with the one given, of any kind (a wall stays a wall only if you pass a
  /// WallSpec); the new one takes over the old one's contact state where the kinds match. Throws
  /// haptic::Error naming the bad field; the old object then stays as it was.
  void update(const WallSpec& wall);
  void update(const SphereSpec& sphere);
  void update(const TangentPlaneSpec& plane);
  void update(const BoxSpec& box);
  void update(const CapsuleSpec& capsule);
  void update(const MeshSpec& mesh);
  /// The server's stability report for the impedance as registered or last updated (empty after
  /// apply_scene, which reports in Client::last_scene_stability()).
  const StabilityReport& stability() const noexcept { return stability_; }

 private:
  friend class Client;
  void replace(const detail::WireObject& object);
  ObjectHandle(std::weak_ptr<detail::ClientCore> core, std::uint64_t key, std::uint64_t id,
               std::uint64_t generation, StabilityReport stability = {})
      : ItemHandle(Kind::kObject, std::move(core), key, id, generation), stability_(stability) {}
  StabilityReport stability_;
};

/// A registered energy field; see detail::ItemHandle for ownership.
class FieldHandle : public detail::ItemHandle {
 public:
  FieldHandle() : ItemHandle(Kind::kField) {}
  /// Replaces the field with the one given, of any kind. Throws haptic::Error naming the bad
  /// field; the old field then stays as it was.
  void update(const SpringFieldSpec& spring);
  void update(const DistanceSpringSpec& spring);
  void update(const PotentialFieldSpec& potential);
  void update(const LinearFieldSpec& linear);
  void update(const ViscousFieldSpec& viscous);
  void update(const DetentFieldSpec& detent);
  void update(const OrientationSpringSpec& spring);
  void update(const OrientationDetentSpec& detent);

  /// An orientation spring's stability report as registered, computed on the device's handle
  /// (its inertia for the mass: kg·m², N·m/rad, N·m·s/rad; docs/scene.md "Orientation fields");
  /// empty for every other field.
  const std::optional<StabilityReport>& stability() const noexcept { return stability_; }

 private:
  friend class Client;
  void replace(const detail::WireField& field);
  FieldHandle(std::weak_ptr<detail::ClientCore> core, std::uint64_t key, std::uint64_t id,
              std::uint64_t generation, std::optional<StabilityReport> stability = std::nullopt)
      : ItemHandle(Kind::kField, std::move(core), key, id, generation), stability_(std::move(stability)) {}
  std::optional<StabilityReport> stability_;
};

/// A whole scene of any objects and fields, for Client::apply_scene; the server numbers them in
/// this order ("scene.objects[i]", "scene.fields[j]" in its messages).
struct SceneSpec {
  using Object = std::variant<WallSpec, SphereSpec, BoxSpec, CapsuleSpec, TangentPlaneSpec, MeshSpec>;
  using Field = std::variant<SpringFieldSpec, DistanceSpringSpec, PotentialFieldSpec, LinearFieldSpec,
                             ViscousFieldSpec, DetentFieldSpec, OrientationSpringSpec,
                             OrientationDetentSpec>;
  std::vector<Object> objects;
  std::vector<Field> fields;
};

/// A scene read back from the server (Client::scene): the objects and fields as each was last
/// given, in id order, with its id and its session (0: the server's own initial scene).
struct RegisteredScene {
  SceneSpec scene;
  std::vector<std::uint64_t> object_ids;
  std::vector<std::uint64_t> field_ids;
  std::vector<std::uint64_t> object_sessions;
  std::vector<std::uint64_t> field_sessions;
};

/// `scene` as a scene file (protobuf JSON, as config/scenes/ holds): what apply_scene_file and
/// `hapticd --scene` read back as the same objects and fields. Throws InvalidArgumentError naming
/// the first element that cannot be written (as apply_scene would refuse it).
std::string scene_json(const SceneSpec& scene);

/// The handles of a scene applied whole (Client::apply_scene, apply_scene_file), in order.
struct AppliedScene {
  std::vector<ObjectHandle> objects;
  std::vector<FieldHandle> fields;
};

/// The handles of a scene applied by Client::apply_scene, each list in the order given.
struct SceneHandles {
  std::vector<ObjectHandle> walls;
  std::vector<ObjectHandle> spheres;
  std::vector<FieldHandle> springs;
};

/// Sees what a Client receives, beside its callbacks (which stay the application's): every
/// accepted State, the server's events and the connection's changes. For tools that sit beside an
/// application, such as haptic::Recorder (haptic/recorder.hpp); attach with Client::observe.
class ReceiveObserver {
 public:
  virtual ~ReceiveObserver() = default;
  /// On the receive thread, for every State datagram accepted (ReceiveCounters::accepted), in the
  /// order read, not only the newest that on_state is handed; not for the sample a Step reply
  /// carries. Holds the receive path up while it runs, and poll_state and wait_for_tick with it:
  /// copy and return.
  virtual void on_sample(const State& state) noexcept = 0;
  /// On a thread of the SDK's, with each server event of this observer's own WatchEvents stream
  /// (ObserveOptions::events), starting with kWatchStarted.
  virtual void on_event(const Event& event) noexcept { (void)event; }
  /// On the SDK's supervisor thread, with each change Client::on_connection would be given.
  virtual void on_connection(const ConnectionChange& change) noexcept { (void)change; }
};

struct ObserveOptions {
  /// Open a WatchEvents stream of the observer's own (the server counts it among its streams):
  /// the Client's on_event callback stays the application's.
  bool events = false;
};

/// An attached ReceiveObserver (Client::observe): move-only; detach() or destruction stops the
/// calls, waiting for one in progress. Harmless if it outlives its Client.
class ObserverHandle {
 public:
  ObserverHandle() = default;
  ObserverHandle(ObserverHandle&& other) noexcept;
  ObserverHandle& operator=(ObserverHandle&& other) noexcept;
  ObserverHandle(const ObserverHandle&) = delete;
  ObserverHandle& operator=(const ObserverHandle&) = delete;
  ~ObserverHandle();
  /// After it returns the observer is called no more. Not from inside the observer's calls.
  void detach() noexcept;
  bool attached() const noexcept { return id_ != 0; }

 private:
  friend class Client;
  ObserverHandle(std::weak_ptr<detail::ClientCore> core, std::uint64_t id)
      : core_(std::move(core)), id_(id) {}
  std::weak_ptr<detail::ClientCore> core_;
  std::uint64_t id_ = 0;
};

/// One session with a hapticd server. Methods may be called from any thread, except that moving,
/// close() and destruction must not race other calls on the same Client.
class Client {
 public:
  /// Connects, opens a session, starts heartbeats and (if state_decimation > 0) the state stream.
  /// Throws ConnectionError, VersionMismatchError, InvalidArgumentError, ResourceExhaustedError.
  explicit Client(ClientConfig config);
  /// Closes the session (never throws); objects still owned by handles go with it.
  ~Client();
  Client(Client&&) noexcept;
  Client& operator=(Client&&) noexcept;
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  ObjectHandle add_wall(const WallSpec& wall);
  ObjectHandle add_sphere(const SphereSpec& sphere);
  FieldHandle add_spring_field(const SpringFieldSpec& spring);
  ObjectHandle add_box(const BoxSpec& box);
  ObjectHandle add_capsule(const CapsuleSpec& capsule);
  ObjectHandle add_tangent_plane(const TangentPlaneSpec& plane);
  /// The server validates the mesh in full (InvalidArgumentError names the bad triangle or edge)
  /// and builds its hierarchy before it reaches the loop.
  ObjectHandle add_mesh(const MeshSpec& mesh);
  FieldHandle add_field(const DistanceSpringSpec& spring);
  FieldHandle add_field(const PotentialFieldSpec& potential);
  FieldHandle add_field(const LinearFieldSpec& linear);
  FieldHandle add_field(const ViscousFieldSpec& viscous);
  FieldHandle add_field(const DetentFieldSpec& detent);
  /// Orientation fields act on a device that measures the tool's orientation; the torque reaches
  /// the hand on one that takes torques (State::torque shows what was commanded).
  FieldHandle add_field(const OrientationSpringSpec& spring);
  FieldHandle add_field(const OrientationDetentSpec& detent);
  /// Replaces this session's scene with a scene file (protobuf's JSON mapping of haptic.v1.Scene,
  /// as hapticd --scene reads); all or nothing, like apply_scene. InvalidArgumentError names the
  /// file, or the server's path ("scene.objects[2].box.half_extents.y: …").
  using FileScene = AppliedScene;  ///< in file order
  FileScene apply_scene_file(const std::string& path);
  /// Stability reports of the objects of the last apply_scene or apply_scene_file, in order.
  const std::vector<StabilityReport>& last_scene_stability() const noexcept {
    return last_scene_stability_;
  }
  /// Energy every object and field has exchanged with the device (GetSceneEnergy). Read from the
  /// scene the loop runs: an item added since its last tick is listed from the next one on (in
  /// lockstep, after the next step()).
  std::vector<ItemEnergy> scene_energy();
  /// Every virtual mass in the scene and where it is now (GetObjectStates); as scene_energy(),
  /// from the loop's last tick.
  std::vector<ObjectState> object_states();
  /// This session's objects and fields as the server holds them (GetScene), each as last given;
  /// with `all_sessions`, every session's and the server's own (a shared scene, to draw it).
  /// Items ramping out are not listed. `scene(false).scene` applied elsewhere makes the same.
  RegisteredScene scene(bool all_sessions = false);
  /// Replaces all of this session's objects and fields at once; if anything is refused, nothing
  /// changes. The server numbers the objects walls first, then spheres ("scene.objects[i]" in its
  /// messages). Handles from earlier calls go stale: their remove() and destructor do nothing and
  /// their update() throws NotFoundError.
  SceneHandles apply_scene(const std::vector<WallSpec>& walls,
                           const std::vector<SphereSpec>& spheres,
                           const std::vector<SpringFieldSpec>& springs);
  /// The same for a scene of every object and field kind; the handles come in the scene's order.
  /// InvalidArgumentError names the item ("ApplyScene: scene.objects[3].box.half_extents.y: …").
  AppliedScene apply_scene(const SceneSpec& scene);

  /// Sets what the server's simulated operator does (FailedPreconditionError on real hardware).
  void set_operator(const OperatorInput& input);
  /// Lockstep servers only: runs `ticks` ticks; returns the index of the last one. Every client
  /// subscribed with lockstep_flow_control gets every due State of them (a slow reader slows the
  /// Step). Its deadline is rpc_timeout plus the ticks' real-time duration (ticks ÷ loop rate).
  std::uint64_t step(std::uint32_t ticks);
  /// Lockstep servers with simulated devices only: puts the server back as it started (devices,
  /// simulated operators, ticks from 1, the server's own scene; this session's items go), so the
  /// same calls reproduce the same run bit for bit. Handles made before go stale (as after
  /// apply_scene); the state stream carries on from tick 1. FailedPreconditionError, changing
  /// nothing, in real time, with a hardware device, or while another session holds items.
  void reset();
  /// Changes the state-stream decimation (every n-th tick; 0 stops it).
  void subscribe(std::uint32_t decimation);

  /// The configuration it was made with.
  const ClientConfig& config() const;
  /// The device, as reported when the session opened.
  const DeviceInfo& device_info() const;
  /// The server's counters (GetStats). With tokens on the server: an ADMIN token only.
  Stats stats();
  /// Every open session (ListSessions). With tokens on the server: an ADMIN token only.
  std::vector<SessionSummary> sessions();
  /// Ends another session (KickSession): its objects and fields ramp out, its client's next call
  /// is NotFoundError, and every watcher sees kSessionClosed with `reason` (at most 256
  /// characters). With tokens on the server: an ADMIN token only.
  void kick_session(std::uint64_t session_id, const std::string& reason = {});
  /// Starts recording the run on the server (StartRecording) into the file `name` in its
  /// recording_dir: every change and every tick's sample, for `hapticd --replay`. ADMIN token only
  /// (with tokens); FailedPreconditionError without recording_dir or while one runs.
  RecordingStatus start_recording(const std::string& name);
  /// Stops it, with its totals (FailedPreconditionError when none runs).
  RecordingStatus stop_recording();
  /// The session's id now (a reconnection after a server restart opens a new one).
  std::uint64_t session_id() const;
  /// How long the server keeps a silent session (no heartbeat, no RPC) before dropping it.
  std::chrono::milliseconds lease_timeout() const;

  /// Called on the SDK's receive thread, the moment a State datagram is read, with the newest
  /// one: the receive thread reads everything that has queued on the socket (recvmmsg) and passes
  /// only the newest, so a callback that runs long is next handed the newest State, and the ones
  /// that arrived meanwhile are counted in ReceiveCounters::callback_skipped (the others passed
  /// over in ::skipped). The heartbeats that hold the lease go from another thread, however long
  /// the callback takes. Never for the sample a Step reply carries. Do not call on_state from
  /// inside it. Pass an empty function to stop; on_state returns once a callback in progress has.
  void on_state(std::function<void(const State&)> callback);
  /// Calls `callback` on a thread of the SDK's with each server event from now on (sessions
  /// opening and closing, leases expiring, scene changes, force and device faults), starting
  /// with kWatchStarted; another call replaces it, an empty function stops it. Throws the
  /// server's refusal (e.g. ResourceExhaustedError past its stream limits). It may run until
  /// on_event({}) or the Client's destruction returns: keep what it uses alive that long. Keep it
  /// short, and do not call on_event from inside it.
  void on_event(std::function<void(const Event&)> callback);
  /// Waits up to `timeout` for a sample newer (by tick) than the last one poll_state or
  /// wait_for_tick returned, and copies the newest into `out`. False on timeout. Samples are
  /// State datagrams and the state a Step reply carries.
  bool poll_state(State& out, std::chrono::milliseconds timeout);
  /// Waits up to `timeout` until a sample of tick >= `tick` has arrived and copies the newest into
  /// `out`. False on timeout. After step() it returns at once: the reply carries that tick's state.
  bool wait_for_tick(std::uint64_t tick, State& out, std::chrono::milliseconds timeout);

  /// Estimated server clock − local steady clock (so server_time ≈ local + offset), taken from
  /// the least-delayed recent sample: max over samples of (server_time − receipt time). It is
  /// biased low by the smallest one-way delay (tens of µs on a LAN). nullopt before any sample.
  std::optional<std::chrono::nanoseconds> clock_offset() const;
  /// How much faster the server's clock runs than this one (dimensionless: 5e-5 is 50 ppm), fitted
  /// by least squares to the least-delayed sample of each window of 2000 (2 s at 1 kHz, up to the
  /// last 16); nullopt before two windows have closed.
  std::optional<double> clock_drift() const;
  /// The server's time at local time `local` (s): the offset carried forward with the drift (the
  /// offset alone until the drift is known), e.g. a frame's display time for predict/interpolate
  /// (haptic/motion.hpp). nullopt before any sample.
  std::optional<double> server_time_at(std::chrono::steady_clock::time_point local) const;

  /// Calls `callback` on the SDK's supervisor thread when the connection is lost and when it
  /// resumes (ConnectionChange; with ClientConfig::reconnect). Another call replaces it, an empty
  /// function stops it. Keep it short: recovery waits for it.
  void on_connection(std::function<void(const ConnectionChange&)> callback);
  ConnectionChange::State connection_state() const;

  /// Stops or resumes UDP heartbeats; stopping simulates a lost client (its lease runs out, and
  /// the client does not reconnect while they are off).
  void set_heartbeats_enabled(bool enabled);
  ReceiveCounters receive_counters() const;

  /// Attaches `observer` (see ReceiveObserver) until the handle detaches it; the Client keeps it
  /// alive meanwhile. With options.events its own event stream opens first: the server's refusal
  /// is thrown (ResourceExhaustedError past its stream limits) and nothing is attached.
  ObserverHandle observe(std::shared_ptr<ReceiveObserver> observer, ObserveOptions options = {});

  /// Closes the session now; throws haptic::Error if the server refuses. After kEnded (the server
  /// ended the session) there is nothing to close, and it only stops the client. Not from inside this
  /// client's on_state, on_event or on_connection callback (closing waits for those threads):
  /// that throws FailedPreconditionError; return from the callback first. For the same reason a
  /// callback must not destroy its Client.
  void close();

 private:
  /// Registers one object or field, already converted for the wire, and hands back its handle.
  ObjectHandle register_object(const detail::WireObject& object);
  FieldHandle register_field(const detail::WireField& field);
  /// Applies a whole scene, already converted for the wire; the handles in its order.
  AppliedScene apply_wire_scene(const detail::WireScene& scene);

  std::vector<StabilityReport> last_scene_stability_;
  std::shared_ptr<detail::ClientCore> core_;
};

}  // namespace haptic
