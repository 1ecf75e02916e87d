#include "haptic/client.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "client_core.hpp"
#include "conversions.hpp"
#include "haptic/io/scene_file.hpp"
#include "haptic/io/session_id.hpp"

namespace haptic {

std::string session_id_text(std::uint64_t session_id) { return io::format_session_id(session_id); }
namespace {

// Client-side checks for obvious mistakes, so they fail fast with a clear message; the server
// validates everything again and stays the authority. Each names the field by the server's path
// for it (`path` is where the item sits in the request: "object", "scene.objects[2]", ...), and
// the caller puts the call's name first (checked()), so a message reads the same whichever side
// found the mistake.
void check_finite(double value, const std::string& field) {
  if (!std::isfinite(value)) throw InvalidArgumentError(field + ": must be finite");
}

void check_finite(const Vec3& v, const std::string& field) {
  check_finite(v.x, field + ".x");
  check_finite(v.y, field + ".y");
  check_finite(v.z, field + ".z");
}

void check_non_negative(double value, const std::string& field) {
  check_finite(value, field);
  if (value < 0.0) throw InvalidArgumentError(field + ": must be >= 0");
}

void check_impedance(const Impedance& impedance, const std::string& path) {
  check_non_negative(impedance.stiffness, path + ".impedance.stiffness");
  check_non_negative(impedance.damping, path + ".impedance.damping");
}

void check(const WallSpec& wall, const std::string& path) {
  check_impedance(wall.impedance, path);
  check_finite(wall.point, path + ".pose.position");
  check_finite(wall.normal, path + ".half_space.normal");
  if (wall.normal == Vec3{}) throw InvalidArgumentError(path + ".half_space.normal: must be non-zero");
}

void check(const SphereSpec& sphere, const std::string& path) {
  check_impedance(sphere.impedance, path);
  check_finite(sphere.center, path + ".pose.position");
  if (!(sphere.radius > 0.0)) throw InvalidArgumentError(path + ".sphere.radius: must be > 0");
}

void check(const SpringFieldSpec& spring, const std::string& path) {
  check_finite(spring.anchor, path + ".spring_to_point.anchor");
  check_non_negative(spring.stiffness, path + ".spring_to_point.stiffness");
  check_non_negative(spring.damping, path + ".spring_to_point.damping");
  check_non_negative(spring.max_force, path + ".spring_to_point.max_force");
}

void check(const OperatorInput& input, const std::string& path) {
  if (input.mode == OperatorInput::Mode::kFollow) {
    check_finite(input.target, path + ".target");
    check_non_negative(input.stiffness, path + ".stiffness");
    check_non_negative(input.damping, path + ".damping");
  } else if (input.mode == OperatorInput::Mode::kPush) {
    check_finite(input.force, path + ".force");
  }
}

// Runs client-side checks for `call`, putting its name first as the server's errors have it
// ("CreateObject: object.sphere.radius: must be > 0").
template <typename Checks>
void checked(const char* call, Checks&& checks) {
  try {
    checks();
  } catch (const InvalidArgumentError& error) {
    throw InvalidArgumentError(std::string(call) + ": " + error.what());
  }
}

// `operation`: the RPC or method the caller is in, named first in the error.
detail::ClientCore& require(const std::shared_ptr<detail::ClientCore>& core, const char* operation) {
  if (!core) throw Error(ErrorCode::kInternal, std::string(operation) + ": the Client was moved from or closed");
  return *core;
}

// The core if it still exists and `generation` is current; null if apply_scene replaced the item.
std::shared_ptr<detail::ClientCore> current_core(const std::weak_ptr<detail::ClientCore>& core,
                                                 std::uint64_t generation) {
  auto locked = core.lock();
  if (locked && locked->scene_generation() != generation) return nullptr;
  return locked;
}

// Handles of items a later apply_scene replaced: the server has already removed the item.
detail::ClientCore& require_current(const std::weak_ptr<detail::ClientCore>& core,
                                    std::uint64_t generation, const char* call, std::uint64_t id) {
  auto locked = core.lock();
  if (!locked) throw Error(ErrorCode::kInternal, std::string(call) + ": the Client was moved from or closed");
  if (locked->scene_generation() != generation) {
    throw NotFoundError(std::string(call) + ": item " + std::to_string(id) +
                        " was replaced by apply_scene or removed by reset");
  }
  return *locked;
}

// Checks (where the SDK has a check for the kind) and converts each item of a list of spec
// variants, naming the offending one ("ApplyScene: scene.objects[2].sphere.radius: ...");
// `add` takes each message.
template <typename Variant, typename Add>
void convert_each(const std::vector<Variant>& items, const char* list, Add add) {
  for (std::size_t i = 0; i < items.size(); ++i) {
    std::visit(
        [&](const auto& item) {
          if constexpr (requires { check(item, std::string()); }) {
            checked("ApplyScene", [&] { check(item, std::string(list) + "[" + std::to_string(i) + "]"); });
          }
          add(detail::to_proto(item));
        },
        items[i]);
  }
}

}  // namespace

// ---- Client ----

Client::Client(ClientConfig config) : core_(std::make_shared<detail::ClientCore>(std::move(config))) {}
Client::~Client() = default;
Client::Client(Client&&) noexcept = default;
Client& Client::operator=(Client&&) noexcept = default;

ObjectHandle Client::register_object(const detail::WireObject& object) {
  detail::ClientCore& core = require(core_, "CreateObject");
  const detail::ClientCore::Created made = core.create_object(object.message);
  return ObjectHandle(core_, made.key, made.ref.id(), core.scene_generation(),
                      detail::from_proto(made.ref.stability()));
}

FieldHandle Client::register_field(const detail::WireField& field) {
  detail::ClientCore& core = require(core_, "CreateField");
  const detail::ClientCore::Created made = core.create_field(field.message);
  std::optional<StabilityReport> stability;
  if (made.ref.has_stability()) stability = detail::from_proto(made.ref.stability());
  return FieldHandle(core_, made.key, made.ref.id(), core.scene_generation(), std::move(stability));
}

ObjectHandle Client::add_wall(const WallSpec& wall) {
  checked("CreateObject", [&] { check(wall, "object"); });
  return register_object({detail::to_proto(wall)});
}

ObjectHandle Client::add_sphere(const SphereSpec& sphere) {
  checked("CreateObject", [&] { check(sphere, "object"); });
  return register_object({detail::to_proto(sphere)});
}

FieldHandle Client::add_spring_field(const SpringFieldSpec& spring) {
  checked("CreateField", [&] { check(spring, "field"); });
  return register_field({detail::to_proto(spring)});
}

ObjectHandle Client::add_box(const BoxSpec& box) {
  return register_object({detail::to_proto(box)});
}

ObjectHandle Client::add_tangent_plane(const TangentPlaneSpec& plane) {
  return register_object({detail::to_proto(plane)});
}

ObjectHandle Client::add_capsule(const CapsuleSpec& capsule) {
  return register_object({detail::to_proto(capsule)});
}

ObjectHandle Client::add_mesh(const MeshSpec& mesh) {
  return register_object({detail::to_proto(mesh)});
}

FieldHandle Client::add_field(const DistanceSpringSpec& spring) {
  return register_field({detail::to_proto(spring)});
}

FieldHandle Client::add_field(const PotentialFieldSpec& potential) {
  return register_field({detail::to_proto(potential)});
}

FieldHandle Client::add_field(const LinearFieldSpec& linear) {
  return register_field({detail::to_proto(linear)});
}

FieldHandle Client::add_field(const ViscousFieldSpec& viscous) {
  return register_field({detail::to_proto(viscous)});
}

FieldHandle Client::add_field(const DetentFieldSpec& detent) {
  return register_field({detail::to_proto(detent)});
}

FieldHandle Client::add_field(const OrientationSpringSpec& spring) {
  return register_field({detail::to_proto(spring)});
}

FieldHandle Client::add_field(const OrientationDetentSpec& detent) {
  return register_field({detail::to_proto(detent)});
}

Client::FileScene Client::apply_scene_file(const std::string& path) {
  v1::Scene scene;
  if (const std::string error = io::read_scene_file(path, scene); !error.empty()) {
    throw InvalidArgumentError("ApplyScene: " + error);
  }
  return apply_wire_scene({scene});
}

namespace {

v1::Scene to_proto_scene(const SceneSpec& spec) {
  v1::Scene scene;
  convert_each(spec.objects, "scene.objects", [&](auto message) { *scene.add_objects() = std::move(message); });
  convert_each(spec.fields, "scene.fields", [&](auto message) { *scene.add_fields() = std::move(message); });
  return scene;
}

}  // namespace

std::string scene_json(const SceneSpec& scene) { return io::scene_json(to_proto_scene(scene)); }

AppliedScene Client::apply_scene(const SceneSpec& spec) { return apply_wire_scene({to_proto_scene(spec)}); }

AppliedScene Client::apply_wire_scene(const detail::WireScene& scene) {
  detail::ClientCore& core = require(core_, "ApplyScene");
  const detail::ClientCore::Applied applied = core.apply_scene(scene.message);
  const v1::ApplySceneResponse& reply = applied.reply;
  const std::uint64_t generation = core.scene_generation();
  last_scene_stability_ = detail::stability_reports(reply);
  AppliedScene handles;
  for (int i = 0; i < reply.object_ids_size(); ++i) {
    handles.objects.push_back(ObjectHandle(core_, applied.object_keys[static_cast<std::size_t>(i)],
                                           reply.object_ids(i), generation));
  }
  for (int i = 0; i < reply.field_ids_size(); ++i) {
    handles.fields.push_back(FieldHandle(core_, applied.field_keys[static_cast<std::size_t>(i)],
                                         reply.field_ids(i), generation));
  }
  return handles;
}

std::vector<ItemEnergy> Client::scene_energy() {
  detail::ClientCore& core = require(core_, "GetSceneEnergy");
  v1::SessionRef request;
  request.set_session_id(core.session_id());
  const auto reply = core.call<v1::SessionRef, v1::SceneEnergy>(
      "GetSceneEnergy", &v1::Haptic::Stub::GetSceneEnergy, request);
  std::vector<ItemEnergy> out;
  for (const auto& item : reply.items()) {
    out.push_back({item.id(), item.session_id(), item.is_object(), item.given_to_device(),
                   item.absorbed_from_device()});
  }
  return out;
}

std::vector<ObjectState> Client::object_states() {
  detail::ClientCore& core = require(core_, "GetObjectStates");
  v1::SessionRef request;
  request.set_session_id(core.session_id());
  const auto reply = core.call<v1::SessionRef, v1::ObjectStates>(
      "GetObjectStates", &v1::Haptic::Stub::GetObjectStates, request);
  std::vector<ObjectState> out;
  for (const auto& object : reply.objects()) {
    out.push_back({object.id(), detail::from_proto(object.position()), detail::from_proto(object.velocity())});
  }
  return out;
}

RegisteredScene Client::scene(bool all_sessions) {
  detail::ClientCore& core = require(core_, "GetScene");
  v1::GetSceneRequest request;
  request.set_session_id(core.session_id());
  request.set_all_sessions(all_sessions);
  const auto reply = core.call<v1::GetSceneRequest, v1::SceneContents>(
      "GetScene", &v1::Haptic::Stub::GetScene, request);
  RegisteredScene out;
  for (const auto& object : reply.scene().objects()) out.scene.objects.push_back(detail::from_proto(object));
  for (const auto& field : reply.scene().fields()) out.scene.fields.push_back(detail::from_proto(field));
  out.object_ids.assign(reply.object_ids().begin(), reply.object_ids().end());
  out.field_ids.assign(reply.field_ids().begin(), reply.field_ids().end());
  out.object_sessions.assign(reply.object_sessions().begin(), reply.object_sessions().end());
  out.field_sessions.assign(reply.field_sessions().begin(), reply.field_sessions().end());
  return out;
}

SceneHandles Client::apply_scene(const std::vector<WallSpec>& walls,
                                 const std::vector<SphereSpec>& spheres,
                                 const std::vector<SpringFieldSpec>& springs) {
  SceneSpec scene;
  scene.objects.insert(scene.objects.end(), walls.begin(), walls.end());
  scene.objects.insert(scene.objects.end(), spheres.begin(), spheres.end());
  scene.fields.insert(scene.fields.end(), springs.begin(), springs.end());
  AppliedScene applied = apply_scene(scene);
  SceneHandles handles;
  for (std::size_t i = 0; i < applied.objects.size(); ++i) {
    (i < walls.size() ? handles.walls : handles.spheres).push_back(std::move(applied.objects[i]));
  }
  handles.springs = std::move(applied.fields);
  return handles;
}

void Client::set_operator(const OperatorInput& input) {
  detail::ClientCore& core = require(core_, "SetOperator");
  checked("SetOperator", [&] { check(input, "input"); });
  v1::SetOperatorRequest request;
  request.set_session_id(core.session_id());
  *request.mutable_input() = detail::to_proto(input);
  core.call<v1::SetOperatorRequest, v1::Empty>("SetOperator", &v1::Haptic::Stub::SetOperator, request);
}

std::uint64_t Client::step(std::uint32_t ticks) {
  detail::ClientCore& core = require(core_, "Step");
  v1::StepRequest request;
  request.set_session_id(core.session_id());
  request.set_ticks(ticks);
  // A Step runs its ticks as fast as the loop and the stream's flow control allow (a slow reader
  // slows it): it is given as long as the same ticks would take in real time, beyond rpc_timeout.
  const double rate_hz = core.device_info().loop_rate_hz > 0.0 ? core.device_info().loop_rate_hz : 1000.0;
  const auto real_time = std::chrono::milliseconds(
      static_cast<std::int64_t>(std::ceil(static_cast<double>(ticks) * 1000.0 / rate_hz)));
  const auto reply = core.call<v1::StepRequest, v1::StepResponse>(
      "Step", &v1::Haptic::Stub::Step, request, core.config().rpc_timeout + real_time);
  core.note_run(reply.run());
  if (reply.has_state()) core.udp().offer(detail::from_proto(reply.state()));
  return reply.tick();
}

void Client::reset() { require(core_, "Reset").reset(); }

void Client::subscribe(std::uint32_t decimation) { require(core_, "SubscribeState").subscribe(decimation); }

const DeviceInfo& Client::device_info() const { return require(core_, "device_info").device_info(); }

Stats Client::stats() {
  detail::ClientCore& core = require(core_, "GetStats");
  v1::SessionRef ref;
  ref.set_session_id(core.session_id());
  return detail::from_proto(
      core.call<v1::SessionRef, v1::Stats>(
      "GetStats", &v1::Haptic::Stub::GetStats, ref));
}

std::vector<SessionSummary> Client::sessions() {
  detail::ClientCore& core = require(core_, "ListSessions");
  v1::SessionRef ref;
  ref.set_session_id(core.session_id());
  const auto list = core.call<v1::SessionRef, v1::SessionList>(
      "ListSessions", &v1::Haptic::Stub::ListSessions, ref);
  std::vector<SessionSummary> out;
  out.reserve(static_cast<std::size_t>(list.sessions_size()));
  for (const v1::SessionSummary& session : list.sessions()) out.push_back(detail::from_proto(session));
  return out;
}

void Client::kick_session(std::uint64_t target, const std::string& reason) {
  detail::ClientCore& core = require(core_, "KickSession");
  v1::KickSessionRequest request;
  request.set_session_id(core.session_id());
  request.set_target_session_id(target);
  request.set_reason(reason);
  core.call<v1::KickSessionRequest, v1::Empty>("KickSession", &v1::Haptic::Stub::KickSession, request);
}

namespace {

RecordingStatus from_proto(const v1::RecordingStatus& status) {
  return {status.path(),    status.start_tick(),          status.samples(),
          status.samples_missed(), status.changes(), status.records_not_written(),
          status.write_error()};
}

}  // namespace

RecordingStatus Client::start_recording(const std::string& name) {
  detail::ClientCore& core = require(core_, "StartRecording");
  v1::StartRecordingRequest request;
  request.set_session_id(core.session_id());
  request.set_name(name);
  return from_proto(core.call<v1::StartRecordingRequest, v1::RecordingStatus>(
      "StartRecording", &v1::Haptic::Stub::StartRecording, request));
}

RecordingStatus Client::stop_recording() {
  detail::ClientCore& core = require(core_, "StopRecording");
  v1::SessionRef request;
  request.set_session_id(core.session_id());
  return from_proto(core.call<v1::SessionRef, v1::RecordingStatus>(
      "StopRecording", &v1::Haptic::Stub::StopRecording, request));
}

std::uint64_t Client::session_id() const { return require(core_, "session_id").session_id(); }

std::chrono::milliseconds Client::lease_timeout() const { return require(core_, "lease_timeout").lease_timeout(); }

void Client::on_state(std::function<void(const State&)> callback) {
  require(core_, "on_state").udp().on_state(std::move(callback));
}

void Client::on_event(std::function<void(const Event&)> callback) {
  if (!callback) {
    require(core_, "WatchEvents").watch_events({});
    return;
  }
  require(core_, "WatchEvents").watch_events(
      [callback = std::move(callback)](const v1::Event& event) { callback(detail::from_proto(event)); });
}

bool Client::poll_state(State& out, std::chrono::milliseconds timeout) {
  return require(core_, "poll_state").udp().poll(out, timeout);
}

bool Client::wait_for_tick(std::uint64_t tick, State& out, std::chrono::milliseconds timeout) {
  return require(core_, "wait_for_tick").udp().wait_for_tick(tick, out, timeout);
}

std::optional<std::chrono::nanoseconds> Client::clock_offset() const {
  return require(core_, "clock_offset").udp().clock_offset();
}

std::optional<double> Client::clock_drift() const { return require(core_, "clock_drift").udp().clock_drift(); }

std::optional<double> Client::server_time_at(std::chrono::steady_clock::time_point local) const {
  return require(core_, "server_time_at").udp().server_time_at(local);
}

void Client::set_heartbeats_enabled(bool enabled) { require(core_, "set_heartbeats_enabled").set_heartbeats_enabled(enabled); }

void Client::on_connection(std::function<void(const ConnectionChange&)> callback) {
  require(core_, "on_connection").on_connection(std::move(callback));
}

ConnectionChange::State Client::connection_state() const { return require(core_, "connection_state").connection_state(); }

const ClientConfig& Client::config() const { return require(core_, "config").config(); }

ObserverHandle Client::observe(std::shared_ptr<ReceiveObserver> observer, ObserveOptions options) {
  if (!observer) throw InvalidArgumentError("observe: observer: empty");
  detail::ClientCore& core = require(core_, "observe");
  const std::uint64_t id = core.observe(std::move(observer), options.events);
  return ObserverHandle(core_, id);
}

ObserverHandle::ObserverHandle(ObserverHandle&& other) noexcept
    : core_(std::move(other.core_)), id_(std::exchange(other.id_, 0)) {}

ObserverHandle& ObserverHandle::operator=(ObserverHandle&& other) noexcept {
  if (this != &other) {
    detach();
    core_ = std::move(other.core_);
    id_ = std::exchange(other.id_, 0);
  }
  return *this;
}

ObserverHandle::~ObserverHandle() { detach(); }

void ObserverHandle::detach() noexcept {
  if (id_ == 0) return;
  if (auto core = core_.lock()) core->unobserve(id_);
  id_ = 0;
  core_.reset();
}

ReceiveCounters Client::receive_counters() const { return require(core_, "receive_counters").counters(); }

void Client::close() {
  if (core_) {
    if (core_->on_callback_thread()) {
      throw FailedPreconditionError(
          "close: called from inside one of this client's callbacks, whose thread closing waits "
          "for; return from the callback and close after");
    }
    auto core = std::move(core_);
    core->close_session();
  }
}

// ---- handles ----

namespace detail {

ItemHandle::ItemHandle(Kind kind, std::weak_ptr<ClientCore> core, std::uint64_t key,
                       std::uint64_t id, std::uint64_t generation)
    : kind_(kind), core_(std::move(core)), key_(key), id_(id), generation_(generation) {}

ItemHandle::ItemHandle(ItemHandle&& other) noexcept
    : kind_(other.kind_),
      core_(std::move(other.core_)),
      key_(std::exchange(other.key_, 0)),
      id_(std::exchange(other.id_, 0)),
      generation_(other.generation_) {}

ItemHandle& ItemHandle::operator=(ItemHandle&& other) noexcept {
  if (this != &other) {
    drop();
    kind_ = other.kind_;
    core_ = std::move(other.core_);
    key_ = std::exchange(other.key_, 0);
    id_ = std::exchange(other.id_, 0);
    generation_ = other.generation_;
  }
  return *this;
}

ItemHandle::~ItemHandle() { drop(); }

std::uint64_t ItemHandle::id() const noexcept {
  if (key_ == 0) return 0;
  if (auto core = core_.lock()) {
    if (const std::uint64_t now = core->server_id(key_); now != 0) return now;
  }
  return id_;
}

void ItemHandle::drop() noexcept {
  if (key_ == 0) return;
  try {
    remove();
  } catch (...) {
    // Swallowed by design: a destructor must not throw; the session's end removes it anyway.
  }
}

ClientCore& ItemHandle::current(const char* call) const {
  return require_current(core_, generation_, call, id_);
}

void ItemHandle::remove() {
  const std::uint64_t key = std::exchange(key_, 0);
  id_ = 0;
  if (key == 0) return;
  if (auto core = current_core(core_, generation_)) {
    if (kind_ == Kind::kObject) {
      core->delete_object(key);
    } else {
      core->delete_field(key);
    }
  }
}

std::uint64_t ItemHandle::release() noexcept {
  const std::uint64_t id = this->id();
  key_ = 0;
  id_ = 0;
  return id;
}

}  // namespace detail

void ObjectHandle::update(const WallSpec& wall) {
  checked("UpdateObject", [&] { check(wall, "object"); });
  replace({detail::to_proto(wall)});
}

void ObjectHandle::update(const SphereSpec& sphere) {
  checked("UpdateObject", [&] { check(sphere, "object"); });
  replace({detail::to_proto(sphere)});
}

void ObjectHandle::update(const TangentPlaneSpec& plane) { replace({detail::to_proto(plane)}); }
void ObjectHandle::update(const BoxSpec& box) { replace({detail::to_proto(box)}); }
void ObjectHandle::update(const CapsuleSpec& capsule) { replace({detail::to_proto(capsule)}); }
void ObjectHandle::update(const MeshSpec& mesh) { replace({detail::to_proto(mesh)}); }

void ObjectHandle::replace(const detail::WireObject& object) {
  stability_ =
      detail::from_proto(current("UpdateObject").update_object(key(), object.message).stability());
}

void FieldHandle::update(const SpringFieldSpec& spring) {
  checked("UpdateField", [&] { check(spring, "field"); });
  replace({detail::to_proto(spring)});
}
void FieldHandle::update(const DistanceSpringSpec& spring) { replace({detail::to_proto(spring)}); }
void FieldHandle::update(const PotentialFieldSpec& potential) { replace({detail::to_proto(potential)}); }
void FieldHandle::update(const LinearFieldSpec& linear) { replace({detail::to_proto(linear)}); }
void FieldHandle::update(const ViscousFieldSpec& viscous) { replace({detail::to_proto(viscous)}); }
void FieldHandle::update(const DetentFieldSpec& detent) { replace({detail::to_proto(detent)}); }
void FieldHandle::update(const OrientationSpringSpec& spring) { replace({detail::to_proto(spring)}); }
void FieldHandle::update(const OrientationDetentSpec& detent) { replace({detail::to_proto(detent)}); }

void FieldHandle::replace(const detail::WireField& field) {
  current("UpdateField").update_field(key(), field.message);
}

}  // namespace haptic
