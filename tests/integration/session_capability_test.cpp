// A session id is a handle, not a capability: another client that reads it (from the events, the
// energy report, anything the server tells it) still cannot act as that session. Raw gRPC, so the
// intruder can send exactly what it likes.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "haptic/io/session_id.hpp"
#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "integration/raw_client.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

class SessionCapability : public ::testing::Test {
 protected:
  v1::OpenSessionResponse open(const std::string& name) {
    v1::OpenSessionResponse response;
    EXPECT_TRUE(client_.open(response, name).ok());
    told_ += response.SerializeAsString();
    return response;
  }

  /// One unary call carrying `secret` (none when empty). Every reply is kept, serialized, so the
  /// test can search everything this client was ever told.
  template <typename Method, typename Request, typename Response>
  grpc::Status call(Method method, const Request& request, Response& response,
                    const std::string& secret) {
    const grpc::Status status = client_.call(method, request, response, secret);
    told_ += response.SerializeAsString() + status.error_message();
    return status;
  }

  test::ServerProcess server_{test::lockstep_config()};
  test::RawClient client_{server_.address()};
  std::string told_;  // everything the server replied, to anyone, in this test
};

TEST_F(SessionCapability, AnotherClientCannotActAsASessionWhoseIdItHasRead) {
  const v1::OpenSessionResponse intruder = open("intruder");
  ASSERT_EQ(intruder.session_secret().size(), io::kSessionSecretSize);
  const std::string& own = intruder.session_secret();

  // The intruder watches the events before the victim arrives.
  grpc::ClientContext watch_context;
  watch_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  watch_context.AddMetadata(io::kSessionSecretMetadataKey, own);
  v1::WatchEventsRequest watch;
  watch.set_session_id(intruder.session_id());
  auto events = client_.stub().WatchEvents(&watch_context, watch);
  v1::Event event;
  ASSERT_TRUE(events->Read(&event));
  ASSERT_EQ(event.kind(), v1::Event::WATCH_STARTED);

  // The victim (its replies are not the intruder's: kept apart).
  const std::string told_before_victim = told_;
  const v1::OpenSessionResponse victim = open("victim");
  ASSERT_NE(victim.session_secret(), own);
  v1::CreateObjectRequest create;
  create.set_session_id(victim.session_id());
  create.mutable_object()->mutable_impedance()->set_stiffness(1000.0);
  create.mutable_object()->mutable_half_space()->mutable_normal()->set_z(1.0);
  v1::ItemRef wall;
  ASSERT_TRUE(call(&v1::Haptic::Stub::CreateObject, create, wall, victim.session_secret()).ok());
  told_ = told_before_victim;

  // What the intruder can read: the victim's id from the event stream and the energy report.
  ASSERT_TRUE(events->Read(&event));
  ASSERT_EQ(event.kind(), v1::Event::SESSION_OPENED);
  const std::uint64_t victim_id = event.session_id();
  EXPECT_EQ(victim_id, victim.session_id());
  told_ += event.SerializeAsString();
  v1::StepRequest tick;  // the loop adopts the scene, and its energy meters, on its next tick
  tick.set_session_id(intruder.session_id());
  tick.set_ticks(1);
  v1::StepResponse ticked;
  ASSERT_TRUE(call(&v1::Haptic::Stub::Step, tick, ticked, own).ok());
  v1::SessionRef me;
  me.set_session_id(intruder.session_id());
  v1::SceneEnergy energy;
  ASSERT_TRUE(call(&v1::Haptic::Stub::GetSceneEnergy, me, energy, own).ok());
  ASSERT_EQ(energy.items_size(), 1);
  EXPECT_EQ(energy.items(0).session_id(), victim_id);  // the owner, shown as a handle
  v1::ObjectStates states;
  ASSERT_TRUE(call(&v1::Haptic::Stub::GetObjectStates, me, states, own).ok());
  v1::Stats stats;
  ASSERT_TRUE(call(&v1::Haptic::Stub::GetStats, me, stats, own).ok());
  v1::DeviceInfo info;
  ASSERT_TRUE(call(&v1::Haptic::Stub::GetDeviceInfo, me, info, own).ok());

  // Nothing it was told holds the victim's secret or its UDP key.
  EXPECT_EQ(told_.find(victim.session_secret()), std::string::npos);
  EXPECT_EQ(told_.find(victim.udp_key()), std::string::npos);

  // Acting as the victim, with no secret, with its own secret, or with a forged one.
  std::string forged = own;
  forged[0] = static_cast<char>(forged[0] ^ 1);
  for (const std::string& secret : {std::string(), own, forged, own.substr(0, 8)}) {
    SCOPED_TRACE(secret.empty() ? "no secret" : "secret of " + std::to_string(secret.size()) + " bytes");
    v1::DeleteRequest remove;
    remove.set_session_id(victim_id);
    remove.set_id(wall.id());
    v1::Empty empty;
    const grpc::Status denied = call(&v1::Haptic::Stub::DeleteObject, remove, empty, secret);
    EXPECT_EQ(denied.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_EQ(denied.error_message().rfind("session_id: session " + io::format_session_id(victim_id), 0), 0u)
        << denied.error_message();

    v1::UpdateObjectRequest update;
    update.set_session_id(victim_id);
    update.set_object_id(wall.id());
    *update.mutable_object() = create.object();
    update.mutable_object()->mutable_impedance()->set_stiffness(1e6);
    v1::ItemRef updated;
    EXPECT_EQ(call(&v1::Haptic::Stub::UpdateObject, update, updated, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::ApplySceneRequest apply;
    apply.set_session_id(victim_id);
    v1::ApplySceneResponse applied;
    EXPECT_EQ(call(&v1::Haptic::Stub::ApplyScene, apply, applied, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::SetOperatorRequest hand;
    hand.set_session_id(victim_id);
    hand.mutable_input()->set_mode(v1::OperatorInput::APPLY_FORCE);
    hand.mutable_input()->mutable_force()->set_z(-20.0);
    EXPECT_EQ(call(&v1::Haptic::Stub::SetOperator, hand, empty, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::SubscribeStateRequest subscribe;
    subscribe.set_session_id(victim_id);
    subscribe.set_decimation(0);
    v1::SubscribeStateResponse subscribed;
    EXPECT_EQ(call(&v1::Haptic::Stub::SubscribeState, subscribe, subscribed, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::StepRequest step;
    step.set_session_id(victim_id);
    step.set_ticks(1);
    v1::StepResponse stepped;
    EXPECT_EQ(call(&v1::Haptic::Stub::Step, step, stepped, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::SessionRef as_victim;
    as_victim.set_session_id(victim_id);
    EXPECT_EQ(call(&v1::Haptic::Stub::CloseSession, as_victim, empty, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    v1::Stats ignored;
    EXPECT_EQ(call(&v1::Haptic::Stub::GetStats, as_victim, ignored, secret).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);

    grpc::ClientContext stream_context;
    stream_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    if (!secret.empty()) stream_context.AddMetadata(io::kSessionSecretMetadataKey, secret);
    v1::WatchEventsRequest watch_as_victim;
    watch_as_victim.set_session_id(victim_id);
    auto stolen = client_.stub().WatchEvents(&stream_context, watch_as_victim);
    v1::Event none;
    EXPECT_FALSE(stolen->Read(&none));
    EXPECT_EQ(stolen->Finish().error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }

  // The victim's session and wall are as it left them, and it can still act for itself.
  v1::SessionRef as_victim;
  as_victim.set_session_id(victim_id);
  v1::SceneEnergy after;
  ASSERT_TRUE(call(&v1::Haptic::Stub::GetSceneEnergy, as_victim, after, victim.session_secret()).ok());
  ASSERT_EQ(after.items_size(), 1);
  EXPECT_EQ(after.items(0).id(), wall.id());
  v1::DeleteRequest remove;
  remove.set_session_id(victim_id);
  remove.set_id(wall.id());
  v1::Empty empty;
  EXPECT_TRUE(call(&v1::Haptic::Stub::DeleteObject, remove, empty, victim.session_secret()).ok());
  watch_context.TryCancel();
}

}  // namespace
}  // namespace haptic
