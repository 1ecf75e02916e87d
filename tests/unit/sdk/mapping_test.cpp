// The SDK's translations: grpc::Status -> exception types, SDK values <-> haptic.v1 messages.
#include <gtest/gtest.h>

#include "conversions.hpp"
#include "haptic/client.hpp"
#include "status_mapping.hpp"

namespace haptic::detail {
namespace {

template <typename ErrorType>
void expect_maps_to(grpc::StatusCode code, const std::string& message = "x: bad") {
  try {
    throw_if_failed(grpc::Status(code, message), "Call");
    FAIL() << "no exception for code " << code;
  } catch (const ErrorType& error) {
    EXPECT_EQ(std::string(error.what()), "Call: " + message);
  }
}

TEST(StatusMapping, EachCodeBecomesItsExceptionWithTheServersMessage) {
  EXPECT_NO_THROW(throw_if_failed(grpc::Status::OK, "Call"));
  expect_maps_to<ConnectionError>(grpc::StatusCode::UNAVAILABLE);
  expect_maps_to<ConnectionError>(grpc::StatusCode::DEADLINE_EXCEEDED);
  expect_maps_to<InvalidArgumentError>(grpc::StatusCode::INVALID_ARGUMENT);
  expect_maps_to<NotFoundError>(grpc::StatusCode::NOT_FOUND);
  expect_maps_to<PermissionDeniedError>(grpc::StatusCode::PERMISSION_DENIED);
  expect_maps_to<ResourceExhaustedError>(grpc::StatusCode::RESOURCE_EXHAUSTED);
  expect_maps_to<FailedPreconditionError>(grpc::StatusCode::FAILED_PRECONDITION);
  expect_maps_to<Error>(grpc::StatusCode::INTERNAL);
}

TEST(StatusMapping, VersionMismatchCarriesBothVersions) {
  try {
    throw_if_failed(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                                 "api_version: client speaks 2, server speaks 3"),
                    "OpenSession");
    FAIL();
  } catch (const VersionMismatchError& error) {
    EXPECT_EQ(error.client_version(), kApiVersion);
    EXPECT_EQ(error.server_version(), 3u);
    EXPECT_EQ(error.code(), ErrorCode::kVersionMismatch);
  }
}

TEST(Conversions, SpecsBecomeTheSchemasMessages) {
  const v1::Object wall = to_proto(WallSpec{{0, 0, 0.01}, {0, 1, 0}, {1000.0, 2.0}});
  EXPECT_TRUE(wall.has_half_space());
  EXPECT_EQ(wall.pose().position().z(), 0.01);
  EXPECT_EQ(wall.half_space().normal().y(), 1.0);
  EXPECT_EQ(wall.impedance().stiffness(), 1000.0);
  EXPECT_EQ(wall.impedance().damping(), 2.0);

  const v1::Object ball = to_proto(SphereSpec{{1, 2, 3}, 0.5, {10.0, 0.0}});
  EXPECT_EQ(ball.sphere().radius(), 0.5);
  EXPECT_EQ(from_proto(ball.pose().position()), (Vec3{1, 2, 3}));

  const v1::Field spring = to_proto(SpringFieldSpec{{0, 0, 1}, 20.0, 0.1, 2.0});
  EXPECT_EQ(spring.spring_to_point().max_force(), 2.0);

  EXPECT_EQ(to_proto(OperatorInput::release()).mode(), v1::OperatorInput::NONE);
  const v1::OperatorInput follow = to_proto(OperatorInput::follow({0, 0, -0.01}, 200.0, 2.0));
  EXPECT_EQ(follow.mode(), v1::OperatorInput::FOLLOW_TARGET);
  EXPECT_EQ(follow.target().z(), -0.01);
  EXPECT_EQ(follow.stiffness(), 200.0);
  const v1::OperatorInput push = to_proto(OperatorInput::push({0, 0, -5.0}));
  EXPECT_EQ(push.mode(), v1::OperatorInput::APPLY_FORCE);
  EXPECT_EQ(push.force().z(), -5.0);
}

TEST(Conversions, ToolStateAndStatsComeBackWhole) {
  v1::ToolState s;
  s.set_tick(42);
  s.set_server_time_s(0.041);
  s.mutable_force()->set_z(5.0);
  s.set_contact_count(1);
  s.set_flags(4);
  const State state = from_proto(s);
  EXPECT_EQ(state.tick, 42u);
  EXPECT_EQ(state.sequence, 0u);
  EXPECT_EQ(state.force.z, 5.0);
  EXPECT_EQ(state.flags, static_cast<std::uint32_t>(kRampingOut));

  v1::Stats stats;
  stats.set_leases_expired(3);
  stats.set_lateness_p99_us(41.0);
  EXPECT_EQ(from_proto(stats).leases_expired, 3u);
  EXPECT_EQ(from_proto(stats).lateness_p99_us, 41.0);
}

TEST(Client, BadConfigurationIsRefusedBeforeAnyConnection) {
  ClientConfig config;
  config.client_name = "";
  EXPECT_THROW(Client{config}, InvalidArgumentError);
  config.client_name = "ok";
  config.heartbeat_period = std::chrono::milliseconds(0);
  EXPECT_THROW(Client{config}, InvalidArgumentError);
}

TEST(Client, UnreachableServerIsAConnectionError) {
  ClientConfig config;
  config.server_address = "127.0.0.1:1";
  config.rpc_timeout = std::chrono::milliseconds(200);
  EXPECT_THROW(Client{config}, ConnectionError);
}

}  // namespace
}  // namespace haptic::detail
