#include "haptic/client.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "client_core.hpp"
#include "conversions.hpp"
#include "haptic/io/scene_file.hpp"

namespace haptic {
namespace {

// Client-side checks for obvious mistakes, so they fail fast with a clear message; the server
// validates everything again and stays the authority.
void check_finite(double value, const char* field) {
  if (!std::isfinite(value)) throw InvalidArgumentError(std::string(field) + ": must be finite");
}

void check_finite(const Vec3& v, const std::string& field) {
  check_finite(v.x, (field + ".x").c_str());
  check_finite(v.y, (field + ".y").c_str());
  check_finite(v.z, (field + ".z").c_str());
}

void check_non_negative(double value, const char* field) {
  check_finite(value, field);
  if (value < 0.0) throw InvalidArgumentError(std::string(field) + ": must be >= 0");
}

void check_impedance(const Impedance& impedance) {
  check_non_negative(impedance.stiffness, "impedance.stiffness");
  check_non_negative(impedance.damping, "impedance.damping");
}

void check(const WallSpec& wall) {
  check_impedance(wall.impedance);
  check_finite(wall.point, "wall.point");
  check_finite(wall.normal, "wall.normal");
  if (wall.normal == Vec3{}) throw InvalidArgumentError("wall.normal: must be non-zero");
}

void check(const SphereSpec& sphere) {
  check_impedance(sphere.impedance);
  check_finite(sphere.center, "sphere.center");
  if (!(sphere.radius > 0.0)) throw InvalidArgumentError("sphere.radius: must be > 0");
}

void check(const SpringFieldSpec& spring) {
  check_finite(spring.anchor, "spring.anchor");
  check_non_negative(spring.stiffness, "spring.stiffness");
  check_non_negative(spring.damping, "spring.damping");
  check_non_negative(spring.max_force, "spring.max_force");
}

void check(const OperatorInput& input) {
  if (input.mode == OperatorInput::Mode::kFollow) {
    check_finite(input.target, "input.target");
    check_non_negative(input.stiffness, "input.stiffness");
    check_non_negative(input.damping, "input.damping");
  } else if (input.mode == OperatorInput::Mode::kPush) {
    check_finite(input.force, "input.force");
  }
}

detail::ClientCore& require(const std::shared_ptr<detail::ClientCore>& core) {
  if (!core) throw Error(ErrorCode::kInternal, "the Client was moved from or closed");
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
  if (!locked) throw Error(ErrorCode::kInternal, "the Client was moved from or closed");
  if (locked->scene_generation() != generation) {
    throw NotFoundError(std::string(call) + ": item " + std::to_string(id) +
                        " was replaced by apply_scene");
  }
  return *locked;
}

// Runs check() on each spec, naming the offending one ("walls[2].impedance...").
template <typename Spec>
void check_each(const std::vector<Spec>& specs, const char* list) {
  for (std::size_t i = 0; i < specs.size(); ++i) {
    try {
      check(specs[i]);
    } catch (const InvalidArgumentError& error) {
      throw InvalidArgumentError(std::string(list) + "[" + std::to_string(i) + "]: " + error.what());
    }
  }
}

// Checks (where the SDK has a check for the kind) and converts each item of a list of spec
// variants, naming the offending one ("scene.objects[2]: ..."); `add` takes each message.
template <typename Variant, typename Add>
void convert_each(const std::vector<Variant>& items, const char* list, Add add) {
  for (std::size_t i = 0; i < items.size(); ++i) {
    std::visit(
        [&](const auto& item) {
          if constexpr (requires { check(item); }) {
            try {
              check(item);
            } catch (const InvalidArgumentError& error) {
              throw InvalidArgumentError(std::string(list) + "[" + std::to_string(i) + "]: " + error.what());
            }
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
  detail::ClientCore& core = require(core_);
  const detail::ClientCore::Created made = core.create_object(object.message);
  return ObjectHandle(core_, made.key, made.ref.id(), core.scene_generation(),
                      detail::from_proto(made.ref.stability()));
}

FieldHandle Client::register_field(const detail::WireField& field) {
  detail::ClientCore& core = require(core_);
  const detail::ClientCore::Created made = core.create_field(field.message);
  return FieldHandle(core_, made.key, made.ref.id(), core.scene_generation());
}

ObjectHandle Client::add_wall(const WallSpec& wall) {
  check(wall);
  return register_object({detail::to_proto(wall)});
}

ObjectHandle Client::add_sphere(const SphereSpec& sphere) {
  check(sphere);
  return register_object({detail::to_proto(sphere)});
}

FieldHandle Client::add_spring_field(const SpringFieldSpec& spring) {
  check(spring);
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

Client::FileScene Client::apply_scene_file(const std::string& path) {
  v1::Scene scene;
  if (const std::string error = io::read_scene_file(path, scene); !error.empty()) {
    throw InvalidArgumentError(error);
  }
  return apply_wire_scene({scene});
}

AppliedScene Client::apply_scene(const SceneSpec& spec) {
  v1::Scene scene;
  convert_each(spec.objects, "scene.objects", [&](auto message) { *scene.add_objects() = std::move(message); });
  convert_each(spec.fields, "scene.fields", [&](auto message) { *scene.add_fields() = std::move(message); });
  return apply_wire_scene({scene});
}

AppliedScene Client::apply_wire_scene(const detail::WireScene& scene) {
  detail::ClientCore& core = require(core_);
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
  v1::SessionRef request;
  request.set_session_id(session_id());
  const auto reply = require(core_).call<v1::SessionRef, v1::SceneEnergy>(
      "GetSceneEnergy", &v1::Haptic::Stub::GetSceneEnergy, request);
  std::vector<ItemEnergy> out;
  for (const auto& item : reply.items()) {
    out.push_back({item.id(), item.session_id(), item.is_object(), item.given_to_device(),
                   item.absorbed_from_device()});
  }
  return out;
}

std::vector<ObjectState> Client::object_states() {
  v1::SessionRef request;
  request.set_session_id(session_id());
  const auto reply = require(core_).call<v1::SessionRef, v1::ObjectStates>(
      "GetObjectStates", &v1::Haptic::Stub::GetObjectStates, request);
  std::vector<ObjectState> out;
  for (const auto& object : reply.objects()) {
    out.push_back({object.id(), detail::from_proto(object.position()), detail::from_proto(object.velocity())});
  }
  return out;
}

RegisteredScene Client::scene(bool all_sessions) {
  v1::GetSceneRequest request;
  request.set_session_id(session_id());
  request.set_all_sessions(all_sessions);
  const auto reply = require(core_).call<v1::GetSceneRequest, v1::SceneContents>(
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
  check_each(walls, "walls");
  check_each(spheres, "spheres");
  check_each(springs, "springs");
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
  check(input);
  v1::SetOperatorRequest request;
  request.set_session_id(session_id());
  *request.mutable_input() = detail::to_proto(input);
  require(core_).call<v1::SetOperatorRequest, v1::Empty>("SetOperator",
                                                         &v1::Haptic::Stub::SetOperator, request);
}

std::uint64_t Client::step(std::uint32_t ticks) {
  v1::StepRequest request;
  request.set_session_id(session_id());
  request.set_ticks(ticks);
  detail::ClientCore& core = require(core_);
  const auto reply =
      core.call<v1::StepRequest, v1::StepResponse>("Step", &v1::Haptic::Stub::Step, request);
  if (reply.has_state()) core.udp().offer(detail::from_proto(reply.state()));
  return reply.tick();
}

void Client::subscribe(std::uint32_t decimation) { require(core_).subscribe(decimation); }

const DeviceInfo& Client::device_info() const { return require(core_).device_info(); }

Stats Client::stats() {
  v1::SessionRef ref;
  ref.set_session_id(session_id());
  return detail::from_proto(
      require(core_).call<v1::SessionRef, v1::Stats>("GetStats", &v1::Haptic::Stub::GetStats, ref));
}

std::vector<SessionSummary> Client::sessions() {
  v1::SessionRef ref;
  ref.set_session_id(session_id());
  const auto list = require(core_).call<v1::SessionRef, v1::SessionList>(
      "ListSessions", &v1::Haptic::Stub::ListSessions, ref);
  std::vector<SessionSummary> out;
  out.reserve(static_cast<std::size_t>(list.sessions_size()));
  for (const v1::SessionSummary& session : list.sessions()) out.push_back(detail::from_proto(session));
  return out;
}

void Client::kick_session(std::uint64_t target, const std::string& reason) {
  v1::KickSessionRequest request;
  request.set_session_id(session_id());
  request.set_target_session_id(target);
  request.set_reason(reason);
  require(core_).call<v1::KickSessionRequest, v1::Empty>("KickSession",
                                                        &v1::Haptic::Stub::KickSession, request);
}

std::uint64_t Client::session_id() const { return require(core_).session_id(); }

std::chrono::milliseconds Client::lease_timeout() const { return require(core_).lease_timeout(); }

void Client::on_state(std::function<void(const State&)> callback) {
  require(core_).udp().on_state(std::move(callback));
}

void Client::on_event(std::function<void(const Event&)> callback) {
  if (!callback) {
    require(core_).watch_events({});
    return;
  }
  require(core_).watch_events(
      [callback = std::move(callback)](const v1::Event& event) { callback(detail::from_proto(event)); });
}

bool Client::poll_state(State& out, std::chrono::milliseconds timeout) {
  return require(core_).udp().poll(out, timeout);
}

bool Client::wait_for_tick(std::uint64_t tick, State& out, std::chrono::milliseconds timeout) {
  return require(core_).udp().wait_for_tick(tick, out, timeout);
}

std::optional<std::chrono::nanoseconds> Client::clock_offset() const {
  return require(core_).udp().clock_offset();
}

std::optional<double> Client::clock_drift() const { return require(core_).udp().clock_drift(); }

std::optional<double> Client::server_time_at(std::chrono::steady_clock::time_point local) const {
  return require(core_).udp().server_time_at(local);
}

void Client::set_heartbeats_enabled(bool enabled) { require(core_).set_heartbeats_enabled(enabled); }

void Client::on_connection(std::function<void(const ConnectionChange&)> callback) {
  require(core_).on_connection(std::move(callback));
}

ConnectionChange::State Client::connection_state() const { return require(core_).connection_state(); }

ReceiveCounters Client::receive_counters() const { return require(core_).counters(); }

void Client::close() {
  if (core_) {
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
  check(wall);
  replace({detail::to_proto(wall)});
}

void ObjectHandle::update(const SphereSpec& sphere) {
  check(sphere);
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
  check(spring);
  replace({detail::to_proto(spring)});
}
void FieldHandle::update(const DistanceSpringSpec& spring) { replace({detail::to_proto(spring)}); }
void FieldHandle::update(const PotentialFieldSpec& potential) { replace({detail::to_proto(potential)}); }
void FieldHandle::update(const LinearFieldSpec& linear) { replace({detail::to_proto(linear)}); }
void FieldHandle::update(const ViscousFieldSpec& viscous) { replace({detail::to_proto(viscous)}); }
void FieldHandle::update(const DetentFieldSpec& detent) { replace({detail::to_proto(detent)}); }

void FieldHandle::replace(const detail::WireField& field) {
  current("UpdateField").update_field(key(), field.message);
}

}  // namespace haptic
