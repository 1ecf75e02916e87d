#pragma once
// The control plane: haptic.v1.Haptic, whichever face carries the call (gRPC: net/grpc_face; JSON
// over HTTP: net/json_face). Every request is validated in full before anything changes
// (INVALID_ARGUMENT names the field); another session's item is PERMISSION_DENIED; limits are
// RESOURCE_EXHAUSTED. Any request renews its session's lease.

#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

#include <grpcpp/support/status.h>

#include "haptic/v1/service.pb.h"
#include "net/access_control.hpp"
#include "net/call_context.hpp"
#include "net/event_hub.hpp"
#include "recording/run_recorder.hpp"
#include "net/scene_store.hpp"
#include "net/session_registry.hpp"
#include "net/state_pacer.hpp"
#include "schema/scene_specs.hpp"
#include "runtime/device.hpp"
#include "runtime/loop_thread.hpp"
#include "engine/operator/simulated_hand.hpp"

/// Every unary call of haptic.v1.Haptic, X(name, request, response), in service.proto's order:
/// the one list the service's handlers, the gRPC face and the JSON face are made from (a test
/// checks it against the service's descriptor). WatchEvents, a server stream, is apart.
#define HAPTIC_V1_UNARY_RPCS(X)                                 \
  X(OpenSession, OpenSessionRequest, OpenSessionResponse)       \
  X(CloseSession, SessionRef, Empty)                            \
  X(CreateObject, CreateObjectRequest, ItemRef)                 \
  X(UpdateObject, UpdateObjectRequest, ItemRef)                 \
  X(DeleteObject, DeleteRequest, Empty)                         \
  X(CreateField, CreateFieldRequest, ItemRef)                   \
  X(UpdateField, UpdateFieldRequest, Empty)                     \
  X(DeleteField, DeleteRequest, Empty)                          \
  X(ApplyScene, ApplySceneRequest, ApplySceneResponse)          \
  X(GetDeviceInfo, SessionRef, DeviceInfo)                      \
  X(GetStats, SessionRef, Stats)                                \
  X(GetSceneEnergy, SessionRef, SceneEnergy)                    \
  X(GetObjectStates, SessionRef, ObjectStates)                  \
  X(GetScene, GetSceneRequest, SceneContents)                   \
  X(ListSessions, SessionRef, SessionList)                      \
  X(KickSession, KickSessionRequest, Empty)                     \
  X(StartRecording, StartRecordingRequest, RecordingStatus)     \
  X(StopRecording, SessionRef, RecordingStatus)                 \
  X(SubscribeState, SubscribeStateRequest, SubscribeStateResponse) \
  X(SetOperator, SetOperatorRequest, Empty)                     \
  X(Step, StepRequest, StepResponse)                            \
  X(Reset, SessionRef, ResetResponse)

namespace haptic::net {

/// One device port as the control plane sees it: what a session bound to it is told and moves.
struct DevicePort {
  const runtime::SampleRing* samples = nullptr;  // the port's tick samples (Step's reply)
  const runtime::DeviceDescription* device = nullptr;
  std::function<void(const engine::HandInput&)> set_hand;  // empty for real hardware
};

struct ServiceDependencies {
  SessionRegistry& sessions;
  SceneStore& scene;
  EventHub& events;
  runtime::LoopThread& loop;
  std::vector<DevicePort> ports;  // port 0 first; not empty
  std::uint16_t udp_port;
  schema::SceneLimits limits;
  std::function<v1::Stats()> stats;
  AccessControl access;  // no tokens: every caller may do everything
  /// A lockstep reset for the session (Reset); empty: refused.
  std::function<grpc::Status(std::uint64_t)> reset;
  /// Where accepted changes are recorded (when a recording runs); none: never.
  recording::RunRecorder* recorder = nullptr;
  /// StartRecording's folder ("" refuses it) and how a recording starts (the header's config).
  std::string recording_dir;
  std::function<std::string(const std::string& path)> start_recording;
  /// In a federation: items may be marked across_sites (else that is refused).
  bool federated = false;
  /// The state sender: waits (up to the timeout) until it has sent what is due through a tick,
  /// true when it has. A lockstep Step with subscribers runs in pieces the sender keeps up with,
  /// so that the loop's ring of samples never laps it. Empty: Step does not wait for it.
  std::function<bool(std::uint64_t tick, std::chrono::milliseconds timeout)> wait_streamed_through;
};

class HapticService {
 public:
  explicit HapticService(ServiceDependencies deps) : deps_(std::move(deps)) {}

  /// Publishes an event stamped with server time.
  void publish_event(v1::Event::Kind kind, std::uint64_t session_id, const std::string& message,
                     std::uint64_t item_id = 0);

  /// SCENE_CHANGED for one item of the session: "object 3 created", with its id.
  void publish_item_change(std::uint64_t session_id, ItemKind kind, std::uint64_t item_id,
                           const char* change);
  /// Hands an accepted change to the recorder, when one records (`fill` makes it only then).
  void record_change(std::uint64_t session_id,
                     const std::function<void(v1::RecordedChange&)>& fill);

  /// Ends the session: its items fade out. Used by CloseSession, KickSession, lease expiry and
  /// expired tokens; `reason` (if any) goes into the event. Logs one line naming the session.
  void end_session(std::uint64_t session_id, v1::Event::Kind why, const std::string& reason = {});

  // haptic.v1.Haptic's calls (proto/haptic/v1/service.proto), one handler each, for both faces.
#define HAPTIC_DECLARE_UNARY(name, Request, Response) \
  grpc::Status name(CallContext* context, const v1::Request* request, v1::Response* response);
  HAPTIC_V1_UNARY_RPCS(HAPTIC_DECLARE_UNARY)
#undef HAPTIC_DECLARE_UNARY
  grpc::Status WatchEvents(CallContext* context, const v1::WatchEventsRequest* request,
                           StreamWriter<v1::Event>* writer);
  /// The state stream for a client without UDP (the HTTP face's WebSocket): each message one
  /// State datagram of the session's port, as the UDP sender encodes it, with a sequence of its
  /// own; until the caller goes (cancelled, or a write fails), the session ends or the server
  /// stops. Renews the session's lease as heartbeats do.
  grpc::Status StreamState(CallContext* context, const v1::StreamStateRequest* request,
                           StreamWriter<std::string>* datagrams);

  /// Ends every session opened with a token that has expired since (a session's heartbeats would
  /// otherwise keep its items in the scene after its holder lost the right to them). Returns how
  /// many it ended.
  std::size_t end_sessions_of_expired_tokens(
      std::chrono::system_clock::time_point now = std::chrono::system_clock::now());

  /// What OpenSession and GetDeviceInfo tell a session bound to device port `port`.
  v1::DeviceInfo device_info(std::uint32_t port = 0) const;

 private:
  double period_s() const { return 1.0 / deps_.loop.config().rate_hz; }
  /// OK when the call's token allows `permission` (AccessControl: UNAUTHENTICATED or
  /// PERMISSION_DENIED naming `call` otherwise), the session exists and the call carries its
  /// secret (the lease is then renewed); NOT_FOUND or PERMISSION_DENIED naming the session otherwise.
  /// `caller` (if given) receives the token's holder and role.
  grpc::Status check_session(const CallContext* context, std::uint64_t session_id,
                             Permission permission, const char* call, Caller* caller = nullptr) const;
  /// The device port an open session is bound to (port 0's if it has just gone).
  const DevicePort& port_of(std::uint64_t session_id) const;

  ServiceDependencies deps_;
  StatePacer state_pacer_;  // StreamState's datagrams, one thread for every stream
};

}  // namespace haptic::net
