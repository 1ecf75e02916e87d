// The control plane's paths no other test takes, over raw gRPC against the real hapticd in
// lockstep: each refusal's exact status and message, and that the refused call changed nothing
// (counts in GetStats, the scene's energy list, the tool's state); every event kind with the
// session and message it carries; a cancelled event stream giving its slot back.
#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "haptic/io/session_id.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "integration/raw_client.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using Code = grpc::StatusCode;
using Stub = v1::Haptic::Stub;
using SteadyClock = std::chrono::steady_clock;

std::string no_session(std::uint64_t id) {
  return "session_id: no open session " + io::format_session_id(id) +
         " (never opened, closed, or its lease expired)";
}

/// Status code and message together, so that a failure shows both.
std::string describe(const grpc::Status& status) {
  return std::to_string(static_cast<int>(status.error_code())) + " \"" + status.error_message() + "\"";
}
std::string describe(Code code, const std::string& message) {
  return std::to_string(static_cast<int>(code)) + " \"" + message + "\"";
}

v1::Vec3 vec(double x, double y, double z) {
  v1::Vec3 v;
  v.set_x(x);
  v.set_y(y);
  v.set_z(z);
  return v;
}

v1::Object sphere(double z, bool shared = false) {
  v1::Object object;
  object.mutable_pose()->mutable_position()->set_z(z);
  object.mutable_impedance()->set_stiffness(500.0);
  object.mutable_sphere()->set_radius(0.005);
  object.set_shared(shared);
  return object;
}

/// A spring pulling the tool onto a point: F = -k (p - anchor) - b v (no clip).
struct SpringSpec {
  v1::Vec3 anchor;
  double stiffness;
  double damping;
};

v1::Field spring(const SpringSpec& spec) {
  v1::Field field;
  auto* s = field.mutable_spring();
  s->mutable_anchor()->set_kind(v1::Distance::POINT);
  *s->mutable_anchor()->mutable_origin() = spec.anchor;
  s->set_stiffness(spec.stiffness);
  s->set_damping(spec.damping);
  return field;
}

/// How far the sampled force is from the one `spec` asks for at the sampled state (largest axis).
double force_error(const SpringSpec& spec, const v1::ToolState& state) {
  const double p[3] = {state.position().x(), state.position().y(), state.position().z()};
  const double v[3] = {state.velocity().x(), state.velocity().y(), state.velocity().z()};
  const double a[3] = {spec.anchor.x(), spec.anchor.y(), spec.anchor.z()};
  const double f[3] = {state.force().x(), state.force().y(), state.force().z()};
  double error = 0.0;
  for (int i = 0; i < 3; ++i) {
    error = std::max(error, std::abs(f[i] - (-spec.stiffness * (p[i] - a[i]) - spec.damping * v[i])));
  }
  return error;
}

double magnitude(const v1::Vec3& v) { return std::sqrt(v.x() * v.x() + v.y() * v.y() + v.z() * v.z()); }

/// One hapticd and one raw client, with the calls the tests repeat.
class Harness {
 public:
  explicit Harness(const std::string& extra_config = {})
      : server_(test::lockstep_config(extra_config)), client_(server_.address()) {}

  v1::OpenSessionResponse open(const std::string& name) {
    v1::OpenSessionResponse session;
    const grpc::Status status = client_.open(session, name);
    EXPECT_TRUE(status.ok()) << describe(status);
    return session;
  }

  template <typename Method, typename Request, typename Response>
  grpc::Status call(Method method, const Request& request, Response& response,
                    const v1::OpenSessionResponse& as) {
    return client_.call(method, request, response, as.session_secret());
  }

  v1::Stats stats(const v1::OpenSessionResponse& as) { return client_.stats(as); }

  v1::StepResponse step(const v1::OpenSessionResponse& as, std::uint32_t ticks) {
    v1::StepRequest request;
    request.set_session_id(as.session_id());
    request.set_ticks(ticks);
    v1::StepResponse response;
    const grpc::Status status = call(&Stub::Step, request, response, as);
    EXPECT_TRUE(status.ok()) << describe(status);
    return response;
  }

  std::uint64_t create_object(const v1::OpenSessionResponse& as, const v1::Object& object) {
    v1::CreateObjectRequest request;
    request.set_session_id(as.session_id());
    *request.mutable_object() = object;
    v1::ItemRef item;
    const grpc::Status status = call(&Stub::CreateObject, request, item, as);
    EXPECT_TRUE(status.ok()) << describe(status);
    return item.id();
  }

  std::uint64_t create_field(const v1::OpenSessionResponse& as, const v1::Field& field) {
    v1::CreateFieldRequest request;
    request.set_session_id(as.session_id());
    *request.mutable_field() = field;
    v1::ItemRef item;
    const grpc::Status status = call(&Stub::CreateField, request, item, as);
    EXPECT_TRUE(status.ok()) << describe(status);
    return item.id();
  }

  /// The scene as the loop runs it (one tick is stepped first, so it has adopted every change):
  /// (id, owner, is_object) of each item.
  std::vector<std::tuple<std::uint64_t, std::uint64_t, bool>> scene(const v1::OpenSessionResponse& as) {
    step(as, 1);
    v1::SessionRef ref;
    ref.set_session_id(as.session_id());
    v1::SceneEnergy energy;
    const grpc::Status status = call(&Stub::GetSceneEnergy, ref, energy, as);
    EXPECT_TRUE(status.ok()) << describe(status);
    std::vector<std::tuple<std::uint64_t, std::uint64_t, bool>> items;
    for (const auto& item : energy.items()) items.emplace_back(item.id(), item.session_id(), item.is_object());
    std::sort(items.begin(), items.end());
    return items;
  }

  /// One WatchEvents call in flight.
  struct Stream {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<v1::Event>> reader;
  };
  std::unique_ptr<Stream> watch(std::uint64_t session_id, const std::string& secret) {
    auto stream = std::make_unique<Stream>();
    stream->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(8));
    if (!secret.empty()) stream->context.AddMetadata(io::kSessionSecretMetadataKey, secret);
    v1::WatchEventsRequest request;
    request.set_session_id(session_id);
    stream->reader = client_.stub().WatchEvents(&stream->context, request);
    return stream;
  }
  std::unique_ptr<Stream> watch(const v1::OpenSessionResponse& as) {
    return watch(as.session_id(), as.session_secret());
  }

  test::RawClient& client() { return client_; }

 private:
  test::ServerProcess server_;
  test::RawClient client_;
};

/// Reads the next event (bounded by the stream's deadline); KIND_UNSPECIFIED if the stream ended.
v1::Event next_event(Harness::Stream& stream) {
  v1::Event event;
  if (!stream.reader->Read(&event)) event.Clear();
  return event;
}

// ---- UpdateField ---------------------------------------------------------------------------

TEST(RpcSurface, UpdateFieldMakesTheFieldExertTheNewSpecsForce) {
  Harness h;
  const auto session = h.open("update-field");
  const SpringSpec before{vec(0.0, 0.0, 0.0), 20.0, 0.5};
  const SpringSpec after{vec(0.01, -0.005, 0.02), 80.0, 1.0};
  const std::uint64_t id = h.create_field(session, spring(before));
  // Past the 50-tick ramp-in, the force at each sampled state is the spring's: exactly.
  v1::StepResponse stepped = h.step(session, 60);
  EXPECT_GT(magnitude(stepped.state().force()), 0.05);
  EXPECT_LT(force_error(before, stepped.state()), 1e-9) << stepped.state().DebugString();

  v1::UpdateFieldRequest update;
  update.set_session_id(session.session_id());
  update.set_field_id(id);
  *update.mutable_field() = spring(after);
  v1::Empty empty;
  const grpc::Status status = h.call(&Stub::UpdateField, update, empty, session);
  ASSERT_TRUE(status.ok()) << describe(status);

  // Past the 50-tick cross-fade only the new spring acts, and the old one's law no longer holds.
  stepped = h.step(session, 60);
  EXPECT_LT(force_error(after, stepped.state()), 1e-9) << stepped.state().DebugString();
  EXPECT_GT(force_error(before, stepped.state()), 1e-3) << stepped.state().DebugString();
  // Still one field, under the same id.
  const v1::Stats stats = h.stats(session);
  EXPECT_EQ(stats.fields(), 1u);
  EXPECT_EQ(stats.objects(), 0u);
  const decltype(h.scene(session)) expected{{id, session.session_id(), false}};
  EXPECT_EQ(h.scene(session), expected);
}

TEST(RpcSurface, UpdateFieldRefusesABadSpecAnUnknownIdAnObjectAndAnotherSessionsField) {
  Harness h;
  const auto owner = h.open("owner");
  const auto other = h.open("other");
  const SpringSpec spec{vec(0.0, 0.0, 0.0), 20.0, 0.5};
  const std::uint64_t field = h.create_field(owner, spring(spec));
  const std::uint64_t object = h.create_object(owner, sphere(-0.05));
  const auto scene_before = h.scene(owner);
  ASSERT_EQ(scene_before.size(), 2u);

  const auto update = [&](const v1::OpenSessionResponse& as, std::uint64_t id, const v1::Field& f) {
    v1::UpdateFieldRequest request;
    request.set_session_id(as.session_id());
    request.set_field_id(id);
    *request.mutable_field() = f;
    v1::Empty empty;
    return h.call(&Stub::UpdateField, request, empty, as);
  };
  SpringSpec negative = spec;
  negative.stiffness = -1.0;
  SpringSpec stronger = spec;
  stronger.stiffness = 500.0;
  const struct {
    const char* what;
    grpc::Status status;
    Code code;
    std::string message;
  } cases[] = {
      {"negative stiffness", update(owner, field, spring(negative)), Code::INVALID_ARGUMENT,
       "field.spring.stiffness: must be finite and in [0, 1e+06], got -1"},
      {"no kind", update(owner, field, v1::Field{}), Code::INVALID_ARGUMENT,
       "field.kind: one of spring_to_point, spring, potential, linear, viscous, detent, "
       "orientation_spring, orientation_detent is required"},
      {"unknown id", update(owner, 987654, spring(stronger)), Code::NOT_FOUND,
       "id: no field with id 987654"},
      {"an object's id", update(owner, object, spring(stronger)), Code::NOT_FOUND,
       "id: no field with id " + std::to_string(object)},
      {"another session's field", update(other, field, spring(stronger)), Code::PERMISSION_DENIED,
       "id: field " + std::to_string(field) + " belongs to another session"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(describe(c.status), describe(c.code, c.message)) << c.what;
  }

  // Nothing changed: the same items, and the field still exerts the spring it was created with.
  const v1::Stats stats = h.stats(owner);
  EXPECT_EQ(stats.fields(), 1u);
  EXPECT_EQ(stats.objects(), 1u);
  EXPECT_EQ(h.scene(owner), scene_before);
  const v1::StepResponse stepped = h.step(owner, 60);
  EXPECT_GT(magnitude(stepped.state().force()), 0.05);
  EXPECT_LT(force_error(spec, stepped.state()), 1e-9) << stepped.state().DebugString();
}

// ---- GetDeviceInfo -------------------------------------------------------------------------

TEST(RpcSurface, AnItemAcrossSitesIsRefusedOutsideAFederationAndNothingChanges) {
  Harness h;
  const auto session = h.open("lab");
  const std::uint64_t kept = h.create_object(session, sphere(-0.05));
  const auto before = h.scene(session);
  v1::Object object = sphere(0.05);
  object.set_across_sites(true);
  v1::CreateObjectRequest create;
  create.set_session_id(session.session_id());
  *create.mutable_object() = object;
  v1::ItemRef item;
  grpc::Status status = h.call(&Stub::CreateObject, create, item, session);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(status.error_message(),
            "object.across_sites: this server is not in a federation (its configuration has no federation section)");
  v1::UpdateObjectRequest update;
  update.set_session_id(session.session_id());
  update.set_object_id(kept);
  *update.mutable_object() = object;
  status = h.call(&Stub::UpdateObject, update, item, session);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  v1::Field field = spring({vec(0.0, 0.0, 0.0), 20.0, 0.5});
  field.set_across_sites(true);
  v1::CreateFieldRequest create_field;
  create_field.set_session_id(session.session_id());
  *create_field.mutable_field() = field;
  status = h.call(&Stub::CreateField, create_field, item, session);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(status.error_message().rfind("field.across_sites: ", 0), 0u) << status.error_message();
  v1::ApplySceneRequest apply;
  apply.set_session_id(session.session_id());
  *apply.mutable_scene()->add_objects() = sphere(0.05);
  *apply.mutable_scene()->add_fields() = field;
  v1::ApplySceneResponse applied;
  status = h.call(&Stub::ApplyScene, apply, applied, session);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(status.error_message().rfind("scene.fields[0].across_sites: ", 0), 0u) << status.error_message();
  EXPECT_EQ(h.scene(session), before);
}

TEST(RpcSurface, GetDeviceInfoRepeatsOpenSessionsDeviceForTheSessionsPort) {
  // A second port with its own point mass (max force 5 N), to show the reply follows the session.
  Harness h(R"("extra_devices": [{"simulated_point_mass": {"max_force": 5}}])");
  const auto first = h.open("port-0");
  v1::SessionRef ref;
  ref.set_session_id(first.session_id());
  v1::DeviceInfo info;
  grpc::Status status = h.call(&Stub::GetDeviceInfo, ref, info, first);
  ASSERT_TRUE(status.ok()) << describe(status);
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(info, first.device()))
      << info.DebugString() << " vs " << first.device().DebugString();
  // The configured defaults of the simulated point mass (server/app/devices.cpp).
  EXPECT_EQ(info.name(), "simulated point mass (3-DOF mass-damper)");
  EXPECT_EQ(info.model(), "point_mass");
  EXPECT_EQ(info.dof(), 3u);
  EXPECT_EQ(info.loop_rate_hz(), 1000.0);
  EXPECT_TRUE(info.simulated());
  EXPECT_EQ(info.max_force(), 20.0);
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(info.workspace_min(), vec(-0.1, -0.1, -0.1)))
      << info.workspace_min().DebugString();
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(info.workspace_max(), vec(0.1, 0.1, 0.1)))
      << info.workspace_max().DebugString();
  EXPECT_EQ(info.capabilities().ByteSizeLong(), 0u);  // a bare mass-damper: none of them

  v1::OpenSessionRequest open;
  open.set_client_name("port-1");
  open.set_api_version(v1::API_VERSION_CURRENT);
  open.set_device_index(1);
  v1::OpenSessionResponse second;
  status = h.client().call(&Stub::OpenSession, open, second, "");
  ASSERT_TRUE(status.ok()) << describe(status);
  ref.set_session_id(second.session_id());
  status = h.call(&Stub::GetDeviceInfo, ref, info, second);
  ASSERT_TRUE(status.ok()) << describe(status);
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(info, second.device()))
      << info.DebugString() << " vs " << second.device().DebugString();
  EXPECT_EQ(info.model(), "point_mass");
  EXPECT_EQ(info.max_force(), 5.0);
}

// ---- UpdateObject, DeleteObject, DeleteField -----------------------------------------------

TEST(RpcSurface, UpdateAndDeleteOfUnknownForeignAndBadItemsAreRefusedAndChangeNothing) {
  Harness h;
  const auto owner = h.open("owner");
  const auto other = h.open("other");
  const std::uint64_t object = h.create_object(owner, sphere(-0.05));
  const std::uint64_t shared = h.create_object(owner, sphere(-0.07, true));
  const std::uint64_t field = h.create_field(owner, spring({vec(0.0, 0.0, 0.02), 10.0, 0.5}));
  const auto scene_before = h.scene(owner);
  ASSERT_EQ(scene_before.size(), 3u);

  const auto update = [&](const v1::OpenSessionResponse& as, std::uint64_t id, const v1::Object& o) {
    v1::UpdateObjectRequest request;
    request.set_session_id(as.session_id());
    request.set_object_id(id);
    *request.mutable_object() = o;
    v1::ItemRef item;
    return h.call(&Stub::UpdateObject, request, item, as);
  };
  const auto remove = [&](auto method, const v1::OpenSessionResponse& as, std::uint64_t id) {
    v1::DeleteRequest request;
    request.set_session_id(as.session_id());
    request.set_id(id);
    v1::Empty empty;
    return h.call(method, request, empty, as);
  };
  v1::Object negative = sphere(-0.05);
  negative.mutable_impedance()->set_stiffness(-1.0);
  v1::Object shapeless = sphere(-0.05);
  shapeless.clear_sphere();
  v1::Object unshared = sphere(-0.07, false);
  const std::string o = std::to_string(object);
  const std::string s = std::to_string(shared);
  const std::string f = std::to_string(field);
  const struct {
    const char* what;
    grpc::Status status;
    Code code;
    std::string message;
  } cases[] = {
      {"UpdateObject: unknown id", update(owner, 987654, sphere(-0.04)), Code::NOT_FOUND,
       "id: no object with id 987654"},
      {"UpdateObject: a field's id", update(owner, field, sphere(-0.04)), Code::NOT_FOUND,
       "id: no object with id " + f},
      {"UpdateObject: another session's", update(other, object, sphere(-0.04)),
       Code::PERMISSION_DENIED, "id: object " + o + " belongs to another session"},
      {"UpdateObject: a shared one made private by another", update(other, shared, unshared),
       Code::PERMISSION_DENIED, "object.shared: only the owner may make a shared object private"},
      {"UpdateObject: negative stiffness", update(owner, object, negative), Code::INVALID_ARGUMENT,
       "object.impedance.stiffness: must be finite and in [0, 1e+06], got -1"},
      {"UpdateObject: no shape", update(owner, object, shapeless), Code::INVALID_ARGUMENT,
       "object.shape: one of half_space, sphere, box, capsule, mesh, tangent_plane is required"},
      {"DeleteObject: unknown id", remove(&Stub::DeleteObject, owner, 987654), Code::NOT_FOUND,
       "id: no object with id 987654"},
      {"DeleteObject: a field's id", remove(&Stub::DeleteObject, owner, field), Code::NOT_FOUND,
       "id: no object with id " + f},
      {"DeleteObject: another session's", remove(&Stub::DeleteObject, other, object),
       Code::PERMISSION_DENIED, "id: object " + o + " belongs to another session"},
      {"DeleteObject: another session's shared one", remove(&Stub::DeleteObject, other, shared),
       Code::PERMISSION_DENIED, "id: object " + s + " is shared, but only its owner may delete it"},
      {"DeleteField: unknown id", remove(&Stub::DeleteField, owner, 987654), Code::NOT_FOUND,
       "id: no field with id 987654"},
      {"DeleteField: an object's id", remove(&Stub::DeleteField, owner, object), Code::NOT_FOUND,
       "id: no field with id " + o},
      {"DeleteField: another session's", remove(&Stub::DeleteField, other, field),
       Code::PERMISSION_DENIED, "id: field " + f + " belongs to another session"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(describe(c.status), describe(c.code, c.message)) << c.what;
  }
  v1::Stats stats = h.stats(owner);
  EXPECT_EQ(stats.objects(), 2u);
  EXPECT_EQ(stats.fields(), 1u);
  EXPECT_EQ(h.scene(owner), scene_before);

  // Removed once, an item is gone: removing it again is NOT_FOUND.
  for (const auto& [method, id, kind] : {std::tuple{&Stub::DeleteField, field, "field"},
                                         std::tuple{&Stub::DeleteObject, object, "object"}}) {
    EXPECT_TRUE(remove(method, owner, id).ok()) << kind;
    EXPECT_EQ(describe(remove(method, owner, id)),
              describe(Code::NOT_FOUND, std::string("id: no ") + kind + " with id " + std::to_string(id)));
  }
  stats = h.stats(owner);
  EXPECT_EQ(stats.objects(), 1u);
  EXPECT_EQ(stats.fields(), 0u);
}

// ---- Unknown sessions ----------------------------------------------------------------------

TEST(RpcSurface, CloseSessionOfAnUnknownSessionOrOfSessionZeroIsNotFound) {
  Harness h;
  const auto session = h.open("closer");
  const auto second = h.open("second");
  v1::Empty empty;
  for (const std::uint64_t id : {std::uint64_t{0}, std::uint64_t{session.session_id() ^ 0x5a5a5a5a5a5a5a5a}}) {
    v1::SessionRef ref;
    ref.set_session_id(id);
    EXPECT_EQ(describe(h.call(&Stub::CloseSession, ref, empty, session)),
              describe(Code::NOT_FOUND, no_session(id)));
  }
  EXPECT_EQ(h.stats(session).sessions(), 2u);
  // A closed session is gone: closing it again is NOT_FOUND too.
  v1::SessionRef ref;
  ref.set_session_id(second.session_id());
  ASSERT_TRUE(h.call(&Stub::CloseSession, ref, empty, second).ok());
  EXPECT_EQ(describe(h.call(&Stub::CloseSession, ref, empty, second)),
            describe(Code::NOT_FOUND, no_session(second.session_id())));
  EXPECT_EQ(h.stats(session).sessions(), 1u);
}

TEST(RpcSurface, EveryUnaryRpcWithAnUnknownSessionIsNotFoundAndDoesNothing) {
  Harness h;
  const auto session = h.open("real");
  const v1::Stats before = h.stats(session);
  // Each request is otherwise valid, so the session is the only thing wrong with it.
  v1::CreateObjectRequest create_object;
  *create_object.mutable_object() = sphere(-0.05);
  v1::UpdateObjectRequest update_object;
  update_object.set_object_id(1);
  *update_object.mutable_object() = sphere(-0.05);
  v1::CreateFieldRequest create_field;
  *create_field.mutable_field() = spring({vec(0, 0, 0), 10.0, 0.0});
  v1::UpdateFieldRequest update_field;
  update_field.set_field_id(1);
  *update_field.mutable_field() = spring({vec(0, 0, 0), 10.0, 0.0});
  v1::DeleteRequest remove;
  remove.set_id(1);
  v1::ApplySceneRequest apply;
  *apply.mutable_scene()->add_objects() = sphere(-0.05);
  v1::SubscribeStateRequest subscribe;
  subscribe.set_decimation(1);
  v1::SetOperatorRequest set_operator;
  set_operator.mutable_input()->set_mode(v1::OperatorInput::APPLY_FORCE);
  set_operator.mutable_input()->mutable_force()->set_z(-1.0);
  v1::StepRequest step;
  step.set_ticks(10);

  int calls = 0;
  for (const std::uint64_t id : {std::uint64_t{session.session_id() ^ 0x0123456789abcdef}, std::uint64_t{0}}) {
    const auto expect_not_found = [&](const char* rpc, auto method, auto request, auto response) {
      request.set_session_id(id);
      // With the real session's secret: it proves nothing about another id.
      EXPECT_EQ(describe(h.call(method, request, response, session)),
                describe(Code::NOT_FOUND, no_session(id)))
          << rpc << " for session " << id;
      ++calls;
    };
    expect_not_found("CloseSession", &Stub::CloseSession, v1::SessionRef{}, v1::Empty{});
    expect_not_found("CreateObject", &Stub::CreateObject, create_object, v1::ItemRef{});
    expect_not_found("UpdateObject", &Stub::UpdateObject, update_object, v1::ItemRef{});
    expect_not_found("DeleteObject", &Stub::DeleteObject, remove, v1::Empty{});
    expect_not_found("CreateField", &Stub::CreateField, create_field, v1::ItemRef{});
    expect_not_found("UpdateField", &Stub::UpdateField, update_field, v1::Empty{});
    expect_not_found("DeleteField", &Stub::DeleteField, remove, v1::Empty{});
    expect_not_found("ApplyScene", &Stub::ApplyScene, apply, v1::ApplySceneResponse{});
    expect_not_found("GetDeviceInfo", &Stub::GetDeviceInfo, v1::SessionRef{}, v1::DeviceInfo{});
    expect_not_found("GetStats", &Stub::GetStats, v1::SessionRef{}, v1::Stats{});
    expect_not_found("GetSceneEnergy", &Stub::GetSceneEnergy, v1::SessionRef{}, v1::SceneEnergy{});
    expect_not_found("GetObjectStates", &Stub::GetObjectStates, v1::SessionRef{}, v1::ObjectStates{});
    expect_not_found("GetScene", &Stub::GetScene, v1::GetSceneRequest{}, v1::SceneContents{});
    expect_not_found("SubscribeState", &Stub::SubscribeState, subscribe, v1::SubscribeStateResponse{});
    expect_not_found("SetOperator", &Stub::SetOperator, set_operator, v1::Empty{});
    expect_not_found("Step", &Stub::Step, step, v1::StepResponse{});
    expect_not_found("Reset", &Stub::Reset, v1::SessionRef{}, v1::ResetResponse{});
  }
  EXPECT_EQ(calls, 2 * 17);  // every session-scoped unary RPC of haptic.v1.Haptic, twice

  // Nothing was created, stepped or set: no ticks ran, and the tool has not been pushed.
  const v1::Stats after = h.stats(session);
  EXPECT_EQ(after.ticks(), before.ticks());
  EXPECT_EQ(after.sessions(), 1u);
  EXPECT_EQ(after.objects(), 0u);
  EXPECT_EQ(after.fields(), 0u);
  const v1::StepResponse stepped = h.step(session, 20);
  EXPECT_EQ(stepped.tick(), before.ticks() + 20);
  EXPECT_EQ(magnitude(stepped.state().velocity()), 0.0);
  EXPECT_EQ(stepped.state().position().z(), 0.02);
}

TEST(RpcSurface, WatchEventsWithAnUnknownSessionEndsNotFound) {
  Harness h;
  const auto session = h.open("watcher");
  for (const std::uint64_t id : {std::uint64_t{session.session_id() ^ 0x1111}, std::uint64_t{0}}) {
    for (const std::string& secret : {session.session_secret(), std::string()}) {
      auto stream = h.watch(id, secret);
      v1::Event event;
      EXPECT_FALSE(stream->reader->Read(&event)) << event.DebugString();
      EXPECT_EQ(describe(stream->reader->Finish()), describe(Code::NOT_FOUND, no_session(id)))
          << "session " << id << (secret.empty() ? " without" : " with") << " a secret";
    }
  }
}

// ---- RESOURCE_EXHAUSTED --------------------------------------------------------------------

TEST(RpcSurface, MaxSessionsRefusesTheNextSessionUntilOneCloses) {
  Harness h(R"("max_sessions": 2, "max_sessions_per_peer": 2)");
  const auto first = h.open("first");
  const auto second = h.open("second");
  auto events = h.watch(first);
  ASSERT_EQ(next_event(*events).kind(), v1::Event::WATCH_STARTED);
  v1::OpenSessionResponse third;
  EXPECT_EQ(describe(h.client().open(third, "third")),
            describe(Code::RESOURCE_EXHAUSTED,
                     "too many sessions open: the server's most is 2 (max_sessions)"));
  EXPECT_EQ(third.session_id(), 0u);
  EXPECT_EQ(h.stats(first).sessions(), 2u);

  v1::SessionRef ref;
  ref.set_session_id(second.session_id());
  v1::Empty empty;
  ASSERT_TRUE(h.call(&Stub::CloseSession, ref, empty, second).ok());
  ASSERT_TRUE(h.client().open(third, "third").ok());
  EXPECT_EQ(h.stats(first).sessions(), 2u);
  // The refused session was never announced: the next events are the close and the later open.
  v1::Event event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::SESSION_CLOSED);
  EXPECT_EQ(event.session_id(), second.session_id());
  event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::SESSION_OPENED);
  EXPECT_EQ(event.session_id(), third.session_id());
  events->context.TryCancel();
}

TEST(RpcSurface, MaxObjectsPerSessionBoundsCreateAndApplySceneAndChangesNothing) {
  Harness h(R"("max_objects_per_session": 3)");
  const auto owner = h.open("owner");
  const auto other = h.open("other");
  h.create_object(owner, sphere(-0.05));
  h.create_object(owner, sphere(-0.06));
  const std::uint64_t field = h.create_field(owner, spring({vec(0, 0, 0.02), 10.0, 0.5}));
  const auto scene_full = h.scene(owner);
  ASSERT_EQ(scene_full.size(), 3u);

  const std::string full = "session already has 3 objects and fields (max_objects_per_session)";
  v1::CreateObjectRequest create_object;
  create_object.set_session_id(owner.session_id());
  *create_object.mutable_object() = sphere(-0.07);
  v1::ItemRef item;
  EXPECT_EQ(describe(h.call(&Stub::CreateObject, create_object, item, owner)),
            describe(Code::RESOURCE_EXHAUSTED, full));
  v1::CreateFieldRequest create_field;
  create_field.set_session_id(owner.session_id());
  *create_field.mutable_field() = spring({vec(0, 0, 0), 5.0, 0.0});
  EXPECT_EQ(describe(h.call(&Stub::CreateField, create_field, item, owner)),
            describe(Code::RESOURCE_EXHAUSTED, full));

  v1::ApplySceneRequest apply;
  apply.set_session_id(owner.session_id());
  for (const double z : {-0.05, -0.06, -0.07}) *apply.mutable_scene()->add_objects() = sphere(z);
  *apply.mutable_scene()->add_fields() = spring({vec(0, 0, 0), 5.0, 0.0});
  v1::ApplySceneResponse applied;
  EXPECT_EQ(describe(h.call(&Stub::ApplyScene, apply, applied, owner)),
            describe(Code::RESOURCE_EXHAUSTED,
                     "scene: 4 objects and fields exceed max_objects_per_session (3)"));
  EXPECT_EQ(applied.object_ids_size(), 0);

  v1::Stats stats = h.stats(owner);
  EXPECT_EQ(stats.objects(), 2u);
  EXPECT_EQ(stats.fields(), 1u);
  EXPECT_EQ(h.scene(owner), scene_full);

  // The cap is per session: another session still creates; and a removed item frees its place.
  const std::uint64_t others = h.create_object(other, sphere(-0.08));
  EXPECT_NE(others, 0u);
  v1::DeleteRequest remove;
  remove.set_session_id(owner.session_id());
  remove.set_id(field);
  v1::Empty empty;
  ASSERT_TRUE(h.call(&Stub::DeleteField, remove, empty, owner).ok());
  create_object.mutable_object()->mutable_pose()->mutable_position()->set_z(-0.075);
  EXPECT_TRUE(h.call(&Stub::CreateObject, create_object, item, owner).ok());
  // A scene of exactly the cap replaces the session's three.
  apply.mutable_scene()->clear_fields();
  ASSERT_TRUE(h.call(&Stub::ApplyScene, apply, applied, owner).ok());
  EXPECT_EQ(applied.object_ids_size(), 3);
  stats = h.stats(owner);
  EXPECT_EQ(stats.objects(), 4u);  // the owner's three and the other's one
  EXPECT_EQ(stats.fields(), 0u);
}

TEST(RpcSurface, MaxSceneBytesBoundsTheWholeSceneFadingVersionsIncluded) {
  // What one item costs is the server's own measure: a budget of one byte refuses the first item
  // and says its cost. Every item without a mesh costs the same.
  std::uint64_t cost = 0;
  {
    Harness h(R"("max_scene_bytes": 1, "max_scene_bytes_per_session": 1, "max_scene_bytes_per_peer": 1)");
    const auto session = h.open("measure");
    v1::CreateObjectRequest create;
    create.set_session_id(session.session_id());
    *create.mutable_object() = sphere(-0.05);
    v1::ItemRef item;
    const grpc::Status status = h.call(&Stub::CreateObject, create, item, session);
    ASSERT_EQ(status.error_code(), Code::RESOURCE_EXHAUSTED) << describe(status);
    const std::string& message = status.error_message();
    ASSERT_EQ(message.rfind("object: ", 0), 0u) << message;
    cost = std::stoull(message.substr(8));
    EXPECT_EQ(message, "object: " + std::to_string(cost) +
                           " more bytes would bring the scene (every session's, fading items "
                           "included) to " + std::to_string(cost) + " bytes, over max_scene_bytes (1)");
    EXPECT_EQ(h.stats(session).objects(), 0u);
  }
  ASSERT_GT(cost, 0u);

  // Room for exactly two items, in all sessions together (every session here is on one host, and
  // the shares are the whole: this is the whole scene's budget).
  const std::string two = std::to_string(2 * cost);
  Harness h("\"max_scene_bytes\": " + two + ", \"max_scene_bytes_per_session\": " + two +
            ", \"max_scene_bytes_per_peer\": " + two);
  const auto first = h.open("first");
  const auto second = h.open("second");
  const std::uint64_t kept = h.create_object(first, sphere(-0.05));
  const std::uint64_t removed = h.create_field(second, spring({vec(0, 0, 0.02), 10.0, 0.5}));
  const auto full_scene = h.scene(first);
  const auto over = [&](const std::string& what, std::uint64_t added, std::uint64_t held) {
    return describe(Code::RESOURCE_EXHAUSTED,
                    what + ": " + std::to_string(added) +
                        " more bytes would bring the scene (every session's, fading items "
                        "included) to " + std::to_string(held + added) +
                        " bytes, over max_scene_bytes (" + std::to_string(2 * cost) + ")");
  };
  v1::CreateObjectRequest create;
  create.set_session_id(first.session_id());
  *create.mutable_object() = sphere(-0.07);
  v1::ItemRef item;
  EXPECT_EQ(describe(h.call(&Stub::CreateObject, create, item, first)), over("object", cost, 2 * cost));
  // An update holds the old version while it fades: it needs room for the new one beside it.
  v1::UpdateObjectRequest update;
  update.set_session_id(first.session_id());
  update.set_object_id(kept);
  *update.mutable_object() = sphere(-0.06);
  EXPECT_EQ(describe(h.call(&Stub::UpdateObject, update, item, first)), over("object", cost, 2 * cost));
  v1::ApplySceneRequest apply;
  apply.set_session_id(first.session_id());
  *apply.mutable_scene()->add_objects() = sphere(-0.06);
  v1::ApplySceneResponse applied;
  EXPECT_EQ(describe(h.call(&Stub::ApplyScene, apply, applied, first)), over("scene", cost, 2 * cost));
  v1::Stats stats = h.stats(first);
  EXPECT_EQ(stats.objects(), 1u);
  EXPECT_EQ(stats.fields(), 1u);
  EXPECT_EQ(h.scene(first), full_scene);

  // A removed item is held until it has faded out (50 ticks), then its room is free again.
  v1::DeleteRequest remove;
  remove.set_session_id(second.session_id());
  remove.set_id(removed);
  v1::Empty empty;
  ASSERT_TRUE(h.call(&Stub::DeleteField, remove, empty, second).ok());
  EXPECT_EQ(describe(h.call(&Stub::CreateObject, create, item, first)), over("object", cost, 2 * cost));
  h.step(first, 60);
  // The server drops faded items on its own time: ask again until it has (bounded).
  grpc::Status created = h.call(&Stub::CreateObject, create, item, first);
  for (int i = 0; i < 250 && !created.ok(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    created = h.call(&Stub::CreateObject, create, item, first);
  }
  EXPECT_TRUE(created.ok()) << describe(created);
  stats = h.stats(first);
  EXPECT_EQ(stats.objects(), 2u);
  EXPECT_EQ(stats.fields(), 0u);
}

// ---- INVALID_ARGUMENT of the remaining RPCs ------------------------------------------------

TEST(RpcSurface, SubscribeStepSetOperatorAndOpenSessionRefuseBadArgumentsAndChangeNothing) {
  Harness h;
  const auto session = h.open("arguments");
  const v1::Stats before = h.stats(session);

  v1::SubscribeStateRequest subscribe;
  subscribe.set_session_id(session.session_id());
  subscribe.set_decimation(1001);
  v1::SubscribeStateResponse subscribed;
  EXPECT_EQ(describe(h.call(&Stub::SubscribeState, subscribe, subscribed, session)),
            describe(Code::INVALID_ARGUMENT, "decimation: must be 0 (stop) to 1000, got 1001"));
  subscribe.set_decimation(1000);
  EXPECT_TRUE(h.call(&Stub::SubscribeState, subscribe, subscribed, session).ok());

  v1::StepRequest step;
  step.set_session_id(session.session_id());
  v1::StepResponse stepped;
  for (const std::uint32_t ticks : {0u, 1'000'001u}) {
    step.set_ticks(ticks);
    EXPECT_EQ(describe(h.call(&Stub::Step, step, stepped, session)),
              describe(Code::INVALID_ARGUMENT,
                       "ticks: must be 1 to 1000000, got " + std::to_string(ticks)));
  }
  EXPECT_EQ(h.stats(session).ticks(), before.ticks());  // no tick ran

  v1::SetOperatorRequest hand;
  hand.set_session_id(session.session_id());
  hand.mutable_input()->set_mode(v1::OperatorInput::APPLY_FORCE);
  hand.mutable_input()->mutable_force()->set_x(std::numeric_limits<double>::quiet_NaN());
  hand.mutable_input()->mutable_force()->set_z(-5.0);
  v1::Empty empty;
  EXPECT_EQ(describe(h.call(&Stub::SetOperator, hand, empty, session)),
            describe(Code::INVALID_ARGUMENT,
                     "input.force.x: must be finite and in [-10000, 10000], got nan"));
  hand.mutable_input()->mutable_force()->set_x(0.0);
  hand.mutable_input()->mutable_force()->set_z(-1e5);
  EXPECT_EQ(describe(h.call(&Stub::SetOperator, hand, empty, session)),
            describe(Code::INVALID_ARGUMENT,
                     "input.force.z: must be finite and in [-10000, 10000], got -100000"));
  // The hand still lets go: nothing pushes the tool from where it started, at rest.
  stepped = h.step(session, 50);
  EXPECT_EQ(stepped.state().position().z(), 0.02);
  EXPECT_EQ(magnitude(stepped.state().velocity()), 0.0);

  const auto open = [&](const std::string& name, std::uint32_t device_index) {
    v1::OpenSessionRequest request;
    request.set_client_name(name);
    request.set_api_version(v1::API_VERSION_CURRENT);
    request.set_device_index(device_index);
    v1::OpenSessionResponse response;
    return h.client().call(&Stub::OpenSession, request, response, "");
  };
  EXPECT_EQ(describe(open("", 0)),
            describe(Code::INVALID_ARGUMENT, "client_name: must be 1 to 64 characters, got 0"));
  EXPECT_EQ(describe(open(std::string(65, 'n'), 0)),
            describe(Code::INVALID_ARGUMENT, "client_name: must be 1 to 64 characters, got 65"));
  for (const std::string& name : {std::string("bell\x07"), std::string("tab\there")}) {
    EXPECT_EQ(describe(open(name, 0)),
              describe(Code::INVALID_ARGUMENT, "client_name: must be printable ASCII"));
  }
  EXPECT_EQ(describe(open("past-the-ports", 1)),
            describe(Code::INVALID_ARGUMENT,
                     "device_index: must be 0 to 0 (this server has 1 device ports), got 1"));
  EXPECT_EQ(h.stats(session).sessions(), 1u);
  EXPECT_TRUE(open(std::string(64, 'n'), 0).ok());  // the longest name allowed
  EXPECT_EQ(h.stats(session).sessions(), 2u);
}

// ---- Events --------------------------------------------------------------------------------

TEST(RpcSurface, EventsOfSessionsAndScenesCarryTheSessionAndTheirMessage) {
  Harness h(R"("lease_timeout_ms": 60000)");
  const auto watcher = h.open("watcher");
  auto events = h.watch(watcher);
  v1::Event event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::WATCH_STARTED);
  EXPECT_EQ(event.session_id(), watcher.session_id());
  EXPECT_EQ(event.message(), "");

  // A refused open, update and scene announce nothing: the next events are the good ones'.
  v1::OpenSessionResponse refused;
  ASSERT_EQ(h.client().open(refused, "").error_code(), Code::INVALID_ARGUMENT);
  const auto actor = h.open("actor-7");
  // Every item a call changes is announced with its id.
  const std::uint64_t object = h.create_object(actor, sphere(-0.05));
  v1::UpdateObjectRequest update;
  update.set_session_id(actor.session_id());
  update.set_object_id(object);
  *update.mutable_object() = sphere(-0.06);
  v1::ItemRef updated;
  ASSERT_TRUE(h.call(&Stub::UpdateObject, update, updated, actor).ok());
  update.set_object_id(object + 100);  // no such object: refused, no event
  ASSERT_EQ(h.call(&Stub::UpdateObject, update, updated, actor).error_code(), Code::NOT_FOUND);
  const std::uint64_t field = h.create_field(actor, spring({{}, 10.0, 0.5}));
  v1::UpdateFieldRequest update_field;
  update_field.set_session_id(actor.session_id());
  update_field.set_field_id(field);
  *update_field.mutable_field() = spring({{}, 20.0, 0.5});
  v1::Empty none;
  ASSERT_TRUE(h.call(&Stub::UpdateField, update_field, none, actor).ok());
  v1::DeleteRequest remove;
  remove.set_session_id(actor.session_id());
  remove.set_id(field);
  ASSERT_TRUE(h.call(&Stub::DeleteField, remove, none, actor).ok());
  remove.set_id(object);
  ASSERT_TRUE(h.call(&Stub::DeleteObject, remove, none, actor).ok());
  ASSERT_EQ(h.call(&Stub::DeleteObject, remove, none, actor).error_code(), Code::NOT_FOUND);
  v1::ApplySceneRequest apply;
  apply.set_session_id(actor.session_id());
  *apply.mutable_scene()->add_objects() = sphere(-0.05);
  *apply.mutable_scene()->add_objects() = sphere(-0.07);
  apply.mutable_scene()->add_fields()->mutable_viscous()->set_damping(-1.0);
  v1::ApplySceneResponse applied;
  ASSERT_EQ(h.call(&Stub::ApplyScene, apply, applied, actor).error_code(), Code::INVALID_ARGUMENT);
  apply.mutable_scene()->mutable_fields(0)->mutable_viscous()->set_damping(0.1);
  ASSERT_TRUE(h.call(&Stub::ApplyScene, apply, applied, actor).ok());
  v1::SessionRef ref;
  ref.set_session_id(actor.session_id());
  v1::Empty empty;
  ASSERT_TRUE(h.call(&Stub::CloseSession, ref, empty, actor).ok());

  const struct {
    v1::Event::Kind kind;
    std::string message;
    std::uint64_t item_id;
  } expected[] = {
      {v1::Event::SESSION_OPENED, "client 'actor-7'", 0},
      {v1::Event::SCENE_CHANGED, "object " + std::to_string(object) + " created", object},
      {v1::Event::SCENE_CHANGED, "object " + std::to_string(object) + " updated", object},
      {v1::Event::SCENE_CHANGED, "field " + std::to_string(field) + " created", field},
      {v1::Event::SCENE_CHANGED, "field " + std::to_string(field) + " updated", field},
      {v1::Event::SCENE_CHANGED, "field " + std::to_string(field) + " deleted", field},
      {v1::Event::SCENE_CHANGED, "object " + std::to_string(object) + " deleted", object},
      {v1::Event::SCENE_CHANGED, "2 objects, 1 fields", 0},
      {v1::Event::SESSION_CLOSED, "3 objects and fields ramping out", 0},
  };
  double last_time = 0.0;
  for (const auto& e : expected) {
    event = next_event(*events);
    EXPECT_EQ(event.kind(), e.kind) << event.DebugString();
    EXPECT_EQ(event.session_id(), actor.session_id()) << event.DebugString();
    EXPECT_EQ(event.message(), e.message) << event.DebugString();
    EXPECT_EQ(event.item_id(), e.item_id) << event.DebugString();
    EXPECT_GE(event.server_time_s(), last_time);
    last_time = event.server_time_s();
  }
  EXPECT_EQ(h.stats(watcher).sessions(), 1u);
  events->context.TryCancel();
}

TEST(RpcSurface, ASilentSessionsLeaseExpiresWithAnEventAndItsItemsGo) {
  // Short, but 25 times the watcher's polling period below: only the silent session lapses even
  // on a loaded machine.
  Harness h(R"("lease_timeout_ms": 500)");
  const auto watcher = h.open("watcher");
  auto events = h.watch(watcher);
  ASSERT_EQ(next_event(*events).kind(), v1::Event::WATCH_STARTED);
  const auto silent = h.open("silent");
  // Its last sign of life is this call, which renews its lease after this instant.
  const auto last_call = SteadyClock::now();
  h.create_object(silent, sphere(-0.05));
  EXPECT_EQ(h.stats(watcher).objects(), 1u);

  // The watcher keeps its own lease with calls (each renews it) while the other lapses.
  v1::Stats stats = h.stats(watcher);
  const auto give_up = SteadyClock::now() + std::chrono::seconds(5);
  while (stats.leases_expired() == 0 && SteadyClock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    stats = h.stats(watcher);
  }
  const auto lapsed_after = SteadyClock::now() - last_call;
  ASSERT_EQ(stats.leases_expired(), 1u);
  EXPECT_GE(lapsed_after, std::chrono::milliseconds(500));  // not before its lease ran out
  EXPECT_EQ(stats.sessions(), 1u);
  EXPECT_EQ(stats.objects(), 0u);

  v1::Event event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::SESSION_OPENED);
  EXPECT_EQ(event.session_id(), silent.session_id());
  event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::SCENE_CHANGED) << event.DebugString();
  event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::LEASE_EXPIRED) << event.DebugString();
  EXPECT_EQ(event.session_id(), silent.session_id());
  EXPECT_EQ(event.message(), "1 objects and fields ramping out");

  // The session is gone for good: its own secret no longer opens it.
  v1::SessionRef ref;
  ref.set_session_id(silent.session_id());
  v1::Stats ignored;
  EXPECT_EQ(describe(h.call(&Stub::GetStats, ref, ignored, silent)),
            describe(Code::NOT_FOUND, no_session(silent.session_id())));
  events->context.TryCancel();
}

TEST(RpcSurface, APotentialWhoseForceWouldOverflowIsRefusedAndTheLoopNeverFaults) {
  Harness h;
  const auto session = h.open("overflow");
  // Every number finite, yet gain (offset − f)⁷ overflows away from the surface: the loop's force
  // would not be finite. (FORCE_FAULT, the event for that, cannot be provoked from outside.)
  v1::Field field;
  auto* potential = field.mutable_potential();
  potential->mutable_distance()->set_kind(v1::Distance::POINT);
  potential->set_kind(v1::PotentialField::POLYNOMIAL);
  potential->set_order(8);
  potential->set_gain(1e303);
  potential->set_offset(10.0);
  v1::CreateFieldRequest request;
  request.set_session_id(session.session_id());
  *request.mutable_field() = field;
  v1::ItemRef made;
  const grpc::Status status = h.call(&Stub::CreateField, request, made, session);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "field.potential.gain: too large: the force 100 m inside the surface overflows, got 1e+303");
  h.step(session, 10);
  EXPECT_EQ(h.stats(session).fields(), 0u);
  EXPECT_EQ(h.stats(session).force_faults(), 0u);
}

TEST(RpcSurface, AWatchdogTripIsReportedAsADeviceFault) {
  // The point mass cannot fail from outside (its workspace stops hold any push); document 004's
  // joystick trips its watchdog when thrown, and a tripped device reads as faulted.
  Harness h(R"("simulated_joystick": {})");
  const auto session = h.open("thrower");
  ASSERT_EQ(session.device().model(), "joystick_004");
  auto events = h.watch(session);
  ASSERT_EQ(next_event(*events).kind(), v1::Event::WATCH_STARTED);
  h.step(session, 200);
  ASSERT_EQ(h.stats(session).device_faults(), 0u);
  v1::SetOperatorRequest hand;
  hand.set_session_id(session.session_id());
  hand.mutable_input()->set_mode(v1::OperatorInput::APPLY_FORCE);
  *hand.mutable_input()->mutable_force() = vec(25.0, 0.0, 0.0);
  v1::Empty empty;
  const grpc::Status status = h.call(&Stub::SetOperator, hand, empty, session);
  ASSERT_TRUE(status.ok()) << describe(status);

  // Tick by tick until the first faulted tick (bounded); then no more ticks: the count is final.
  v1::StepResponse stepped;
  v1::Stats stats = h.stats(session);
  for (int i = 0; i < 400 && stats.device_faults() == 0; ++i) {
    stepped = h.step(session, 1);
    stats = h.stats(session);
  }
  ASSERT_EQ(stats.device_faults(), 1u);
  EXPECT_EQ(magnitude(stepped.state().force()), 0.0);  // zero force on a faulted tick
  const v1::Event event = next_event(*events);
  EXPECT_EQ(event.kind(), v1::Event::DEVICE_FAULT) << event.DebugString();
  EXPECT_EQ(event.session_id(), 0u);  // the device's, not a session's
  EXPECT_EQ(event.message(), "1 ticks with a failed or non-finite device reading; zero force");
  events->context.TryCancel();
}

// ---- WatchEvents cancellation --------------------------------------------------------------

TEST(RpcSurface, ACancelledEventStreamFreesItsPlaceForTheNext) {
  Harness h(R"("max_event_streams_per_session": 1)");
  const auto session = h.open("canceller");
  auto first = h.watch(session);
  ASSERT_EQ(next_event(*first).kind(), v1::Event::WATCH_STARTED);
  // The message names the session as every log and tool does (hex), and the setting; not the
  // call, which the client's own error names.
  const std::string full = "session " + io::format_session_id(session.session_id()) +
                           " already holds 1 event streams, the most one session may "
                           "(max_event_streams_per_session = 1)";
  {
    auto refused = h.watch(session);
    EXPECT_EQ(next_event(*refused).kind(), v1::Event::KIND_UNSPECIFIED);
    EXPECT_EQ(describe(refused->reader->Finish()), describe(Code::RESOURCE_EXHAUSTED, full));
  }

  first->context.TryCancel();
  EXPECT_EQ(next_event(*first).kind(), v1::Event::KIND_UNSPECIFIED);
  EXPECT_EQ(first->reader->Finish().error_code(), Code::CANCELLED);

  // The server sees the cancellation on its own time: ask again until it has (bounded). Until
  // then a refusal can only be the cap's.
  std::unique_ptr<Harness::Stream> next;
  int attempts = 0;
  const auto give_up = SteadyClock::now() + std::chrono::seconds(5);
  while (SteadyClock::now() < give_up) {
    ++attempts;
    auto stream = h.watch(session);
    if (next_event(*stream).kind() == v1::Event::WATCH_STARTED) {
      next = std::move(stream);
      break;
    }
    EXPECT_EQ(describe(stream->reader->Finish()), describe(Code::RESOURCE_EXHAUSTED, full));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_NE(next, nullptr) << "no new stream accepted within 5 s of the cancel";
  std::printf("  a new stream accepted at attempt %d after the cancel\n", attempts);

  // The new stream is live and the cap still holds.
  const auto other = h.open("other");
  v1::Event event = next_event(*next);
  EXPECT_EQ(event.kind(), v1::Event::SESSION_OPENED);
  EXPECT_EQ(event.session_id(), other.session_id());
  {
    auto refused = h.watch(session);
    EXPECT_EQ(next_event(*refused).kind(), v1::Event::KIND_UNSPECIFIED);
    EXPECT_EQ(describe(refused->reader->Finish()), describe(Code::RESOURCE_EXHAUSTED, full));
  }
  next->context.TryCancel();
}

}  // namespace
}  // namespace haptic
