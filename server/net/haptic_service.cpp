#include "net/haptic_service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <span>
#include <thread>

#include "haptic/io/session_id.hpp"
#include "haptic/io/session_secret.hpp"
#include "net/read_back.hpp"
#include "schema/stability.hpp"

namespace haptic::net {
namespace {

/// The device as the stability report models it: its tool point as a mass-damper.
schema::DeviceMassDamper mass_damper(const runtime::DeviceDescription& device) {
  return {device.apparent_mass, device.apparent_damping, device.delay_s, device.actuator_lag_s};
}

/// The device's handle about each axis as an inertia-damper, for an orientation spring's report.
schema::DeviceMassDamper inertia_damper(const runtime::DeviceDescription& device) {
  return {device.apparent_inertia, device.apparent_rotational_damping};
}

/// An object accepted although its own report says it will not be stable: the client has the
/// report; the operator sees it in the log.
void log_if_unstable(const v1::StabilityReport& report, std::uint64_t session_id,
                     std::uint64_t item_id, const char* kind = "object") {
  if (report.warning().empty()) return;
  spdlog::warn("session {}: {} {} accepted but {}", io::format_session_id(session_id), kind, item_id,
               report.warning());
}

constexpr std::uint32_t kApiVersion = v1::API_VERSION_CURRENT;
constexpr std::uint32_t kMaxDecimation = 1000;
constexpr std::uint32_t kMaxStepTicks = 1'000'000;
// SubscribeState's lockstep flow-control window, in datagrams: at least a few acknowledgements'
// worth (the SDK acknowledges every quarter window), at most what a 64 MiB socket buffer holds.
constexpr std::uint32_t kMinAckWindow = 16;
constexpr std::uint32_t kMaxAckWindow = 65536;

grpc::Status invalid(const std::string& message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, message};
}

/// An item marked across_sites on a server outside any federation: FAILED_PRECONDITION naming it.
grpc::Status not_federated(const std::string& path) {
  return {grpc::StatusCode::FAILED_PRECONDITION,
          path + ".across_sites: this server is not in a federation (its configuration has no federation section)"};
}

std::string check_client_name(const std::string& name) {
  if (name.empty() || name.size() > 64) {
    return "client_name: must be 1 to 64 characters, got " + std::to_string(name.size());
  }
  for (const char c : name) {
    if (!std::isprint(static_cast<unsigned char>(c))) {
      return "client_name: must be printable ASCII";
    }
  }
  return {};
}

}  // namespace

grpc::Status HapticService::check_session(const CallContext* context,
                                          std::uint64_t session_id, Permission permission,
                                          const char* call, Caller* caller) const {
  if (auto status = deps_.access.authorize(*context, permission, call, caller, context->peer_host());
      !status.ok()) {
    return status;
  }
  const std::optional<std::string> sent = context->metadata(io::kSessionSecretMetadataKey);
  std::span<const std::uint8_t> secret;
  if (sent) secret = {reinterpret_cast<const std::uint8_t*>(sent->data()), sent->size()};
  switch (session_id == 0 ? Access::kNoSuchSession : deps_.sessions.authorize(session_id, secret)) {
    case Access::kGranted:
      return grpc::Status::OK;
    case Access::kNoSuchSession:
      if (auto reason = deps_.sessions.ended_reason(session_id)) {
        return {grpc::StatusCode::PERMISSION_DENIED,
                "session_id: session " + io::format_session_id(session_id) + " was " + *reason +
                    "; open a new one only if you may"};
      }
      return {grpc::StatusCode::NOT_FOUND,
              "session_id: no open session " + io::format_session_id(session_id) +
                  " (never opened, closed, or its lease expired)"};
    case Access::kWrongSecret:
      break;
  }
  return {grpc::StatusCode::PERMISSION_DENIED,
          "session_id: session " + io::format_session_id(session_id) +
              (secret.empty() ? " needs its session secret, and this call carries none"
                              : " belongs to another client: this call's session secret is not its") +
              " (only the client that opened a session may act for it; it sends the secret "
              "OpenSession returned as metadata " + io::kSessionSecretMetadataKey + ")"};
}

const DevicePort& HapticService::port_of(std::uint64_t session_id) const {
  const std::uint32_t index = deps_.sessions.device_index_of(session_id).value_or(0);
  return deps_.ports[index < deps_.ports.size() ? index : 0];
}

void HapticService::publish_event(v1::Event::Kind kind, std::uint64_t session_id,
                                  const std::string& message, std::uint64_t item_id) {
  v1::Event event;
  event.set_kind(kind);
  event.set_session_id(session_id);
  event.set_item_id(item_id);
  event.set_server_time_s(static_cast<double>(deps_.loop.server_time_ns()) * 1e-9);
  event.set_message(message);
  deps_.events.publish(event);
}

void HapticService::publish_item_change(std::uint64_t session_id, ItemKind kind,
                                        std::uint64_t item_id, const char* change) {
  publish_event(v1::Event::SCENE_CHANGED, session_id,
                std::string(kind == ItemKind::kObject ? "object " : "field ") +
                    std::to_string(item_id) + " " + change,
                item_id);
}

void HapticService::record_change(std::uint64_t session_id,
                                  const std::function<void(v1::RecordedChange&)>& fill) {
  if (deps_.recorder == nullptr || !deps_.recorder->active()) return;
  v1::RecordedChange change;
  change.set_session_id(session_id);
  fill(change);
  deps_.recorder->record(std::move(change));
}

void HapticService::end_session(std::uint64_t session_id, v1::Event::Kind why,
                                const std::string& reason) {
  const std::size_t faded = deps_.scene.remove_session(session_id);
  record_change(session_id, [](v1::RecordedChange& change) { change.set_ended(true); });
  const std::string how =
      !reason.empty() ? reason
                      : (why == v1::Event::LEASE_EXPIRED ? "lease expired" : "closed by its client");
  spdlog::info("session {}: {}; {} objects and fields ramping out",
               io::format_session_id(session_id), how, faded);
  publish_event(why, session_id,
                (reason.empty() ? std::string() : reason + "; ") + std::to_string(faded) +
                    " objects and fields ramping out");
  deps_.events.end_session(session_id);
}

std::size_t HapticService::end_sessions_of_expired_tokens(std::chrono::system_clock::time_point now) {
  if (!deps_.access.enabled()) return 0;
  std::size_t ended = 0;
  for (const SessionInfo& session : deps_.sessions.list()) {
    if (session.caller.token_name.empty() || !deps_.access.expired(session.caller.token_name, now)) {
      continue;
    }
    const std::string reason = "ended: token '" + session.caller.token_name + "' expired";
    if (!deps_.sessions.end(session.id, reason)) continue;  // closed meanwhile
    end_session(session.id, v1::Event::SESSION_CLOSED, reason);
    ++ended;
  }
  return ended;
}

v1::DeviceInfo HapticService::device_info(std::uint32_t port) const {
  const runtime::DeviceDescription& device = *deps_.ports[port].device;
  v1::DeviceInfo info;
  info.set_name(device.name);
  info.set_dof(device.dof);
  *info.mutable_workspace_min() = schema::to_proto(device.workspace_min);
  *info.mutable_workspace_max() = schema::to_proto(device.workspace_max);
  info.set_max_force(device.max_force);
  info.set_loop_rate_hz(deps_.loop.config().rate_hz);
  info.set_simulated(device.simulated);
  info.set_model(device.model);
  const runtime::DeviceCapabilities& has = device.capabilities;
  v1::DeviceCapabilities& caps = *info.mutable_capabilities();
  caps.set_gravity(has.gravity);
  caps.set_brakes(has.brakes);
  caps.set_flexible_modes(has.flexible_modes);
  caps.set_friction(has.friction);
  caps.set_force_sensor(has.force_sensor);
  caps.set_quantized_position(has.quantized_position);
  caps.set_state_estimator(has.state_estimator);
  caps.set_disturbance_observer(has.disturbance_observer);
  caps.set_orientation(has.orientation);
  caps.set_torque(has.torque);
  info.set_buttons(device.buttons);
  info.set_max_torque(device.max_torque);
  return info;
}

grpc::Status HapticService::OpenSession(CallContext* context, const v1::OpenSessionRequest* request,
                                        v1::OpenSessionResponse* response) {
  Caller caller;
  if (auto status = deps_.access.authorize(*context, Permission::kObserve, "OpenSession", &caller,
                                              context->peer_host());
      !status.ok()) {
    return status;
  }
  if (request->api_version() != kApiVersion) {
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "api_version: client speaks " + std::to_string(request->api_version()) +
                ", server speaks " + std::to_string(kApiVersion)};
  }
  if (auto error = check_client_name(request->client_name()); !error.empty()) return invalid(error);
  if (request->device_index() >= deps_.ports.size()) {
    return invalid("device_index: must be 0 to " + std::to_string(deps_.ports.size() - 1) +
                   " (this server has " + std::to_string(deps_.ports.size()) +
                   " device ports), got " + std::to_string(request->device_index()));
  }
  std::string refusal;
  const auto session = deps_.sessions.open(request->client_name(), request->device_index(),
                                           context->peer_host(), &refusal, caller);
  if (!session) return {grpc::StatusCode::RESOURCE_EXHAUSTED, refusal};
  response->set_session_id(session->id);
  response->set_udp_key(std::string(session->key.begin(), session->key.end()));
  response->set_session_secret(std::string(session->secret.begin(), session->secret.end()));
  response->set_udp_port(deps_.udp_port);
  response->set_api_version(kApiVersion);
  *response->mutable_device() = device_info(request->device_index());
  response->set_lease_timeout_ms(static_cast<std::uint32_t>(deps_.sessions.lease_timeout().count()));
  response->set_server_time_s(static_cast<double>(deps_.loop.server_time_ns()) * 1e-9);
  const std::string opened_by =
      "client '" + request->client_name() + "'" +
      (caller.token_name.empty()
           ? std::string()
           : " with token '" + caller.token_name + "' (" + role_name(caller.role) + ")");
  spdlog::info("session {}: opened by {} from {} on device {}", io::format_session_id(session->id),
               opened_by, session->peer.empty() ? "an unknown host" : session->peer,
               request->device_index());
  publish_event(v1::Event::SESSION_OPENED, session->id, opened_by);
  record_change(session->id, [&](v1::RecordedChange& change) {
    change.mutable_opened()->set_client_name(request->client_name());
    change.mutable_opened()->set_device_index(request->device_index());
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::CloseSession(CallContext* context, const v1::SessionRef* request,
                                         v1::Empty*) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "CloseSession"); !status.ok()) return status;
  deps_.sessions.close(request->session_id());
  end_session(request->session_id(), v1::Event::SESSION_CLOSED);
  return grpc::Status::OK;
}

grpc::Status HapticService::CreateObject(CallContext* context, const v1::CreateObjectRequest* request,
                                         v1::ItemRef* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "CreateObject"); !status.ok()) return status;
  if (request->object().across_sites() && !deps_.federated) return not_federated("object");
  engine::ObjectSpec spec;
  if (auto error = schema::to_object_spec(request->object(), "object", deps_.limits, spec); !error.empty()) {
    return invalid(error);
  }
  std::uint64_t id = 0;
  if (auto status = deps_.scene.create(request->session_id(), ItemKind::kObject, spec, id,
                                      {std::make_shared<const v1::Object>(request->object()), {}});
      !status.ok()) {
    return status;
  }
  response->set_id(id);
  *response->mutable_stability() =
      schema::stability_report(spec, mass_damper(*port_of(request->session_id()).device), period_s(),
                       request->object().impedance().transparency_optimal_damping(),
                       request->object().impedance().virtual_coupling());
  log_if_unstable(response->stability(), request->session_id(), id);
  publish_item_change(request->session_id(), ItemKind::kObject, id, "created");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_object_created()->set_id(id);
    *change.mutable_object_created()->mutable_object() = request->object();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::UpdateObject(CallContext* context, const v1::UpdateObjectRequest* request,
                                         v1::ItemRef* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "UpdateObject"); !status.ok()) return status;
  if (request->object().across_sites() && !deps_.federated) return not_federated("object");
  engine::ObjectSpec spec;
  if (auto error = schema::to_object_spec(request->object(), "object", deps_.limits, spec); !error.empty()) {
    return invalid(error);
  }
  if (auto status =
          deps_.scene.update(request->session_id(), ItemKind::kObject, request->object_id(), spec,
                             {std::make_shared<const v1::Object>(request->object()), {}});
      !status.ok()) {
    return status;
  }
  response->set_id(request->object_id());
  *response->mutable_stability() =
      schema::stability_report(spec, mass_damper(*port_of(request->session_id()).device), period_s(),
                       request->object().impedance().transparency_optimal_damping(),
                       request->object().impedance().virtual_coupling());
  log_if_unstable(response->stability(), request->session_id(), request->object_id());
  publish_item_change(request->session_id(), ItemKind::kObject, request->object_id(), "updated");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_object_updated()->set_id(request->object_id());
    *change.mutable_object_updated()->mutable_object() = request->object();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::DeleteObject(CallContext* context, const v1::DeleteRequest* request,
                                         v1::Empty*) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "DeleteObject"); !status.ok()) return status;
  if (auto status = deps_.scene.remove(request->session_id(), ItemKind::kObject, request->id());
      !status.ok()) {
    return status;
  }
  publish_item_change(request->session_id(), ItemKind::kObject, request->id(), "deleted");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_object_deleted()->set_id(request->id());
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::CreateField(CallContext* context, const v1::CreateFieldRequest* request,
                                        v1::ItemRef* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "CreateField"); !status.ok()) return status;
  if (request->field().across_sites() && !deps_.federated) return not_federated("field");
  engine::FieldSpec spec;
  if (auto error = schema::to_field_spec(request->field(), "field", deps_.limits, spec); !error.empty()) {
    return invalid(error);
  }
  std::uint64_t id = 0;
  if (auto status = deps_.scene.create(request->session_id(), ItemKind::kField, spec, id,
                                      {{}, std::make_shared<const v1::Field>(request->field())});
      !status.ok()) {
    return status;
  }
  response->set_id(id);
  if (const auto* spring = std::get_if<engine::OrientationSpringSpec>(&spec.kind)) {
    *response->mutable_stability() =
        schema::stability_report(*spring, inertia_damper(*port_of(request->session_id()).device), period_s());
    log_if_unstable(response->stability(), request->session_id(), id, "orientation spring");
  }
  publish_item_change(request->session_id(), ItemKind::kField, id, "created");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_field_created()->set_id(id);
    *change.mutable_field_created()->mutable_field() = request->field();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::UpdateField(CallContext* context, const v1::UpdateFieldRequest* request,
                                        v1::Empty*) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "UpdateField"); !status.ok()) return status;
  if (request->field().across_sites() && !deps_.federated) return not_federated("field");
  engine::FieldSpec spec;
  if (auto error = schema::to_field_spec(request->field(), "field", deps_.limits, spec); !error.empty()) {
    return invalid(error);
  }
  if (auto status =
          deps_.scene.update(request->session_id(), ItemKind::kField, request->field_id(), spec,
                             {{}, std::make_shared<const v1::Field>(request->field())});
      !status.ok()) {
    return status;
  }
  publish_item_change(request->session_id(), ItemKind::kField, request->field_id(), "updated");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_field_updated()->set_id(request->field_id());
    *change.mutable_field_updated()->mutable_field() = request->field();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::DeleteField(CallContext* context, const v1::DeleteRequest* request,
                                        v1::Empty*) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "DeleteField"); !status.ok()) return status;
  if (auto status = deps_.scene.remove(request->session_id(), ItemKind::kField, request->id());
      !status.ok()) {
    return status;
  }
  publish_item_change(request->session_id(), ItemKind::kField, request->id(), "deleted");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    change.mutable_field_deleted()->set_id(request->id());
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::GetSceneEnergy(CallContext* context, const v1::SessionRef* request,
                                           v1::SceneEnergy* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "GetSceneEnergy"); !status.ok()) return status;
  for (const engine::ItemEnergyTotals& item : deps_.scene.energy()) {
    v1::ItemEnergy& out = *response->add_items();
    out.set_id(item.id);
    out.set_session_id(item.session_id);
    out.set_is_object(item.is_object);
    out.set_given_to_device(item.given);
    out.set_absorbed_from_device(item.absorbed);
  }
  return grpc::Status::OK;
}

grpc::Status HapticService::GetObjectStates(CallContext* context, const v1::SessionRef* request,
                                            v1::ObjectStates* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "GetObjectStates"); !status.ok()) return status;
  *response = to_object_states(deps_.scene.motions());
  return grpc::Status::OK;
}

grpc::Status HapticService::GetScene(CallContext* context, const v1::GetSceneRequest* request,
                                     v1::SceneContents* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "GetScene"); !status.ok()) return status;
  *response = to_scene_contents(deps_.scene.read(request->session_id(), request->all_sessions()));
  return grpc::Status::OK;
}

grpc::Status HapticService::ApplyScene(CallContext* context, const v1::ApplySceneRequest* request,
                                       v1::ApplySceneResponse* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "ApplyScene"); !status.ok()) return status;
  for (int i = 0; i < request->scene().objects_size() && !deps_.federated; ++i) {
    if (request->scene().objects(i).across_sites()) return not_federated("scene.objects[" + std::to_string(i) + "]");
  }
  for (int i = 0; i < request->scene().fields_size() && !deps_.federated; ++i) {
    if (request->scene().fields(i).across_sites()) return not_federated("scene.fields[" + std::to_string(i) + "]");
  }
  // Validate everything first: one bad item rejects the whole scene and changes nothing.
  schema::SceneSpecs specs;
  if (auto error = schema::to_scene_specs(request->scene(), "scene.", deps_.limits, specs); !error.empty()) {
    return invalid(error);
  }
  const std::vector<engine::ObjectSpec>& objects = specs.objects;
  const std::vector<engine::FieldSpec>& fields = specs.fields;
  std::vector<std::uint64_t> object_ids, field_ids;
  if (auto status = deps_.scene.replace_session_scene(request->session_id(), objects, fields,
                                                      object_ids, field_ids, &request->scene());
      !status.ok()) {
    return status;
  }
  const runtime::DeviceDescription& device = *port_of(request->session_id()).device;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    *response->add_object_stability() = schema::stability_report(
        objects[i], mass_damper(device), period_s(),
        request->scene().objects(static_cast<int>(i)).impedance().transparency_optimal_damping(),
        request->scene().objects(static_cast<int>(i)).impedance().virtual_coupling());
    log_if_unstable(response->object_stability(static_cast<int>(i)), request->session_id(),
                    object_ids[i]);
  }
  for (auto id : object_ids) response->add_object_ids(id);
  for (auto id : field_ids) response->add_field_ids(id);
  publish_event(v1::Event::SCENE_CHANGED, request->session_id(),
                std::to_string(object_ids.size()) + " objects, " +
                    std::to_string(field_ids.size()) + " fields");
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    *change.mutable_scene_applied()->mutable_scene() = request->scene();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::GetDeviceInfo(CallContext* context, const v1::SessionRef* request,
                                          v1::DeviceInfo* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "GetDeviceInfo"); !status.ok()) return status;
  *response = device_info(deps_.sessions.device_index_of(request->session_id()).value_or(0));
  return grpc::Status::OK;
}

grpc::Status HapticService::GetStats(CallContext* context, const v1::SessionRef* request,
                                     v1::Stats* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kAdmin, "GetStats"); !status.ok()) return status;
  *response = deps_.stats();
  return grpc::Status::OK;
}

grpc::Status HapticService::WatchEvents(CallContext* context,
                                        const v1::WatchEventsRequest* request,
                                        StreamWriter<v1::Event>* writer) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "WatchEvents"); !status.ok()) return status;
  std::string refusal;
  auto watcher = deps_.events.watch(request->session_id(), refusal,
                                    deps_.sessions.peer_of(request->session_id()),
                                    deps_.sessions.token_of(request->session_id()));
  if (!watcher) return {grpc::StatusCode::RESOURCE_EXHAUSTED, refusal};
  // Tell the client the watch is live, so it can act knowing it will miss nothing from here on.
  v1::Event started;
  started.set_kind(v1::Event::WATCH_STARTED);
  started.set_session_id(request->session_id());
  started.set_server_time_s(static_cast<double>(deps_.loop.server_time_ns()) * 1e-9);
  writer->write(started);
  // Until the client cancels, or the session (or the server) ends: a watch never outlives its
  // session, so a client cannot keep threads by abandoning sessions.
  while (!context->cancelled() && !watcher->finished()) {
    if (auto event = watcher->next(std::chrono::milliseconds(100))) {
      if (!writer->write(*event)) break;
    }
  }
  deps_.events.unwatch(watcher);
  return grpc::Status::OK;
}

grpc::Status HapticService::StreamState(CallContext* context, const v1::StreamStateRequest* request,
                                        StreamWriter<std::string>* datagrams) {
  const std::uint64_t session_id = request->session_id();
  if (auto status = check_session(context, session_id, Permission::kObserve, "StreamState"); !status.ok()) {
    return status;
  }
  const double loop_rate = deps_.loop.config().rate_hz;
  const double most = std::min(1000.0, loop_rate);
  if (!(request->rate_hz() >= 1.0 && request->rate_hz() <= most)) {
    return invalid("rate_hz: must be 1 to " + std::to_string(static_cast<int>(most)) +
                   " (at most the loop's rate, " + std::to_string(static_cast<int>(loop_rate)) +
                   " Hz), got " + std::to_string(request->rate_hz()));
  }
  const std::optional<wire::Key> key = deps_.sessions.key_of(session_id);
  if (!key) return {grpc::StatusCode::NOT_FOUND, "session_id: the session has ended"};
  const std::optional<std::string> secret_text = context->metadata(io::kSessionSecretMetadataKey);
  const std::string secret = secret_text.value_or(std::string());
  const std::span<const std::uint8_t> secret_bytes(reinterpret_cast<const std::uint8_t*>(secret.data()),
                                                   secret.size());
  // The datagrams go out on the pacer's thread; this one waits, renewing the session's lease as a
  // heartbeat would, a few times within it, until the stream ends.
  StatePacer::Stream stream;
  stream.session_id = session_id;
  stream.key = *key;
  stream.ring = port_of(session_id).samples;
  stream.period = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(1.0 / request->rate_hz()));
  stream.sink = [datagrams](const std::string& datagram) { return datagrams->write(datagram); };
  const std::uint64_t id = state_pacer_.add(std::move(stream));
  const auto renew_every = std::clamp(deps_.sessions.lease_timeout() / 4, std::chrono::milliseconds(1),
                                      std::chrono::milliseconds(50));
  grpc::Status status = grpc::Status::OK;
  while (!context->cancelled() && state_pacer_.running(id) && !port_of(session_id).samples->stopping()) {
    std::this_thread::sleep_for(renew_every);
    if (deps_.sessions.authorize(session_id, secret_bytes) != Access::kGranted) {
      status = {grpc::StatusCode::NOT_FOUND, "session_id: the session has ended"};
      break;
    }
  }
  state_pacer_.remove(id);
  return status;
}

grpc::Status HapticService::ListSessions(CallContext* context, const v1::SessionRef* request,
                                         v1::SessionList* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kAdmin, "ListSessions");
      !status.ok()) {
    return status;
  }
  const double now_s = static_cast<double>(deps_.loop.server_time_ns()) * 1e-9;
  const SteadyClock::time_point now = SteadyClock::now();
  for (const SessionInfo& session : deps_.sessions.list()) {
    v1::SessionSummary& out = *response->add_sessions();
    out.set_session_id(session.id);
    out.set_client_name(session.client_name);
    out.set_device_index(session.device_index);
    out.set_peer(session.peer);
    out.set_token_name(session.caller.token_name);
    out.set_role(session.caller.role);
    out.set_opened_s(now_s - std::chrono::duration<double>(now - session.opened).count());
  }
  return grpc::Status::OK;
}

grpc::Status HapticService::KickSession(CallContext* context,
                                        const v1::KickSessionRequest* request, v1::Empty*) {
  Caller caller;
  if (auto status =
          check_session(context, request->session_id(), Permission::kAdmin, "KickSession", &caller);
      !status.ok()) {
    return status;
  }
  constexpr std::size_t kMaxReason = 256;
  if (request->reason().size() > kMaxReason) {
    return invalid("reason: at most " + std::to_string(kMaxReason) + " characters, got " +
                   std::to_string(request->reason().size()));
  }
  const std::string by = caller.token_name.empty() ? "an admin" : "'" + caller.token_name + "'";
  const std::string reason =
      "ended by " + by + (request->reason().empty() ? "" : ": " + request->reason());
  if (!deps_.sessions.end(request->target_session_id(), reason)) {
    return {grpc::StatusCode::NOT_FOUND, "target_session_id: no open session " +
                                             io::format_session_id(request->target_session_id())};
  }
  end_session(request->target_session_id(), v1::Event::SESSION_CLOSED, reason);
  return grpc::Status::OK;
}

grpc::Status HapticService::StartRecording(CallContext* context,
                                           const v1::StartRecordingRequest* request,
                                           v1::RecordingStatus* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kAdmin, "StartRecording");
      !status.ok()) {
    return status;
  }
  if (deps_.recorder == nullptr || deps_.recording_dir.empty() || !deps_.start_recording) {
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "this server has no recording_dir: set one in its configuration to record on request "
            "(or start it with --record FILE)"};
  }
  const std::string& name = request->name();
  const bool allowed_characters = std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
  if (name.empty() || name.size() > 64 || name.front() == '.' || !allowed_characters) {
    return invalid("name: 1 to 64 of A-Z a-z 0-9 . _ - not starting with '.', got '" +
                   name.substr(0, 80) + "'");
  }
  const std::string path = deps_.recording_dir + "/" + name;
  if (const std::string error = deps_.start_recording(path); !error.empty()) {
    return {grpc::StatusCode::FAILED_PRECONDITION, error};
  }
  response->set_path(path);
  response->set_start_tick(deps_.recorder->start_tick());
  return grpc::Status::OK;
}

grpc::Status HapticService::StopRecording(CallContext* context, const v1::SessionRef* request,
                                          v1::RecordingStatus* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kAdmin, "StopRecording");
      !status.ok()) {
    return status;
  }
  const std::string path = deps_.recorder != nullptr ? deps_.recorder->path() : std::string();
  const auto end = deps_.recorder != nullptr ? deps_.recorder->stop("stopped") : std::nullopt;
  if (!end) return {grpc::StatusCode::FAILED_PRECONDITION, "no recording is running"};
  response->set_path(path);
  response->set_samples(end->samples());
  response->set_samples_missed(end->samples_missed());
  response->set_changes(end->changes());
  response->set_records_not_written(end->records_not_written());
  response->set_write_error(end->write_error());
  return grpc::Status::OK;
}

grpc::Status HapticService::SubscribeState(CallContext* context,
                                           const v1::SubscribeStateRequest* request,
                                           v1::SubscribeStateResponse* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kObserve, "SubscribeState"); !status.ok()) return status;
  if (request->decimation() > kMaxDecimation) {
    return invalid("decimation: must be 0 (stop) to " + std::to_string(kMaxDecimation) + ", got " +
                   std::to_string(request->decimation()));
  }
  if (const std::uint32_t window = request->ack_window();
      window != 0 && (window < kMinAckWindow || window > kMaxAckWindow)) {
    return invalid("ack_window: must be 0 (no flow control) or " + std::to_string(kMinAckWindow) +
                   " to " + std::to_string(kMaxAckWindow) + ", got " + std::to_string(window));
  }
  // Flow control is lockstep's: in real time a stale sample is worse than a lost one, and
  // nothing may wait on a client.
  const std::uint32_t window =
      deps_.loop.config().mode == runtime::TimeMode::kLockstep ? request->ack_window() : 0;
  // The stream starts with the next tick the loop runs: samples the sender has yet to catch up
  // with predate the subscription.
  const auto endpoint_known = deps_.sessions.subscribe(request->session_id(), request->decimation(),
                                                       deps_.loop.completed_ticks() + 1, window);
  response->set_udp_endpoint_known(endpoint_known.value_or(false));
  response->set_ack_window(request->decimation() > 0 ? window : 0);
  return grpc::Status::OK;
}

grpc::Status HapticService::SetOperator(CallContext* context, const v1::SetOperatorRequest* request,
                                        v1::Empty*) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "SetOperator"); !status.ok()) return status;
  const DevicePort& port = port_of(request->session_id());
  if (!port.set_hand) {
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "this port's device is not simulated (it is behind a driver): there is no simulated operator to set"};
  }
  engine::HandInput hand;
  if (auto error = schema::to_hand_input(request->input(), "input", deps_.limits, hand); !error.empty()) {
    return invalid(error);
  }
  port.set_hand(hand);
  record_change(request->session_id(), [&](v1::RecordedChange& change) {
    *change.mutable_operator_input() = request->input();
  });
  return grpc::Status::OK;
}

grpc::Status HapticService::Reset(CallContext* context, const v1::SessionRef* request,
                                  v1::ResetResponse* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "Reset"); !status.ok()) return status;
  if (!deps_.reset) return {grpc::StatusCode::FAILED_PRECONDITION, "this server cannot be reset"};
  if (auto status = deps_.reset(request->session_id()); !status.ok()) return status;
  response->set_run(deps_.loop.run());
  publish_event(v1::Event::RESET, request->session_id(),
                "lockstep reset: ticks count from 1 again and the scene is as the server started");
  return grpc::Status::OK;
}

grpc::Status HapticService::Step(CallContext* context, const v1::StepRequest* request,
                                 v1::StepResponse* response) {
  if (auto status = check_session(context, request->session_id(), Permission::kControl, "Step"); !status.ok()) return status;
  if (deps_.loop.config().mode != runtime::TimeMode::kLockstep) {
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "the server runs in REAL_TIME; start it with time_mode LOCKSTEP"};
  }
  if (request->ticks() == 0 || request->ticks() > kMaxStepTicks) {
    return invalid("ticks: must be 1 to " + std::to_string(kMaxStepTicks) + ", got " +
                   std::to_string(request->ticks()));
  }
  runtime::LoopThread::Stepped stepped;
  // The run recorder and the state sender read every tick's sample from a ring of 1024: with
  // either at work, step in pieces of half a ring and wait for them after each, so that no
  // sample is overwritten before they have read it. The sender may itself be waiting on a
  // flow-controlled client (at most kAckStallTimeout before it sends on without waiting); a wait
  // that still runs out only lets the next piece go, and what the ring then loses is counted.
  const bool recording = deps_.recorder != nullptr && deps_.recorder->active();
  const bool streaming = deps_.wait_streamed_through && deps_.sessions.any_subscribed();
  if (recording || streaming) {
    constexpr std::uint32_t kPiece = runtime::SampleRing::kCapacity / 2;
    for (std::uint32_t left = request->ticks(); left > 0;) {
      const std::uint32_t piece = std::min(left, kPiece);
      stepped = deps_.loop.step(piece);
      left -= piece;
      if (recording) deps_.recorder->wait_written_through(stepped.tick, std::chrono::seconds(5));
      if (streaming) deps_.wait_streamed_through(stepped.tick, std::chrono::seconds(5));
    }
  } else {
    stepped = deps_.loop.step(request->ticks());
  }
  const std::uint64_t tick = stepped.tick;
  response->set_tick(tick);
  response->set_run(stepped.run);
  response->set_server_time_s(static_cast<double>(deps_.loop.server_time_ns()) * 1e-9);
  runtime::TickSample sample;
  if (port_of(request->session_id()).samples->read(tick, sample)) {
    *response->mutable_state() = to_tool_state(sample);
  }
  return grpc::Status::OK;
}

}  // namespace haptic::net
