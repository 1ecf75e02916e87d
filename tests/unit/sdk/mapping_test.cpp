// The SDK's translations: grpc::Status -> exception types, SDK values <-> haptic.v1 messages.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

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
  expect_maps_to<UnauthenticatedError>(grpc::StatusCode::UNAUTHENTICATED);
  expect_maps_to<ResourceExhaustedError>(grpc::StatusCode::RESOURCE_EXHAUSTED);
  expect_maps_to<FailedPreconditionError>(grpc::StatusCode::FAILED_PRECONDITION);
  expect_maps_to<Error>(grpc::StatusCode::INTERNAL);
}

TEST(StatusMapping, VersionMismatchCarriesBothVersions) {
  try {
    throw_if_failed(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                                 "api_version: client speaks 3, server speaks 4"),
                    "OpenSession");
    FAIL();
  } catch (const VersionMismatchError& error) {
    EXPECT_EQ(error.client_version(), kApiVersion);
    EXPECT_EQ(error.server_version(), 4u);
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
  // Every field set to a value of its own: a field dropped or swapped in the conversion shows.
  v1::ToolState s;
  s.set_tick(42);
  s.set_server_time_s(0.041);
  const auto vec = [](v1::Vec3* v, double x, double y, double z) {
    v->set_x(x);
    v->set_y(y);
    v->set_z(z);
  };
  vec(s.mutable_position(), 1.0, 2.0, 3.0);
  vec(s.mutable_velocity(), 4.0, 5.0, 6.0);
  vec(s.mutable_force(), 7.0, 8.0, 9.0);
  vec(s.mutable_proxy(), 10.0, 11.0, 12.0);
  s.set_contact_count(13);
  s.set_flags(4);
  const State state = from_proto(s);
  EXPECT_EQ(state.tick, 42u);
  EXPECT_EQ(state.sequence, 0u);  // a Step reply's sample has no datagram sequence
  EXPECT_EQ(state.server_time, 0.041);
  EXPECT_EQ(state.position, (Vec3{1.0, 2.0, 3.0}));
  EXPECT_EQ(state.velocity, (Vec3{4.0, 5.0, 6.0}));
  EXPECT_EQ(state.force, (Vec3{7.0, 8.0, 9.0}));
  EXPECT_EQ(state.proxy, (Vec3{10.0, 11.0, 12.0}));
  EXPECT_EQ(state.contact_count, 13u);
  EXPECT_EQ(state.flags, static_cast<std::uint32_t>(kRampingOut));

  v1::Stats stats;
  const google::protobuf::Descriptor& descriptor = *v1::Stats::descriptor();
  const google::protobuf::Reflection& reflection = *v1::Stats::GetReflection();
  // Field number n gets the value 100 + n, whatever its type.
  for (int i = 0; i < descriptor.field_count(); ++i) {
    const google::protobuf::FieldDescriptor& field = *descriptor.field(i);
    const int value = 100 + field.number();
    switch (field.cpp_type()) {
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT64: reflection.SetUInt64(&stats, &field, value); break;
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT32: reflection.SetUInt32(&stats, &field, value); break;
      case google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE: reflection.SetDouble(&stats, &field, value); break;
      default: ADD_FAILURE() << "Stats." << field.name() << " has a type this test does not set";
    }
  }
  const Stats out = from_proto(stats);
  // One line per proto field: a new one without its line here fails the count below.
  const std::vector<std::pair<const char*, double>> seen = {
      {"ticks", static_cast<double>(out.ticks)},
      {"achieved_rate_hz", out.achieved_rate_hz},
      {"lateness_p50_us", out.lateness_p50_us},
      {"lateness_p99_us", out.lateness_p99_us},
      {"lateness_max_us", out.lateness_max_us},
      {"overruns", static_cast<double>(out.overruns)},
      {"sessions", static_cast<double>(out.sessions)},
      {"objects", static_cast<double>(out.objects)},
      {"fields", static_cast<double>(out.fields)},
      {"datagrams_sent", static_cast<double>(out.datagrams_sent)},
      {"datagrams_received", static_cast<double>(out.datagrams_received)},
      {"datagrams_dropped", static_cast<double>(out.datagrams_dropped)},
      {"force_faults", static_cast<double>(out.force_faults)},
      {"force_saturations", static_cast<double>(out.force_saturations)},
      {"leases_expired", static_cast<double>(out.leases_expired)},
      {"send_delay_p50_us", out.send_delay_p50_us},
      {"send_delay_p99_us", out.send_delay_p99_us},
      {"device_faults", static_cast<double>(out.device_faults)},
      {"passivity_active_ticks", static_cast<double>(out.passivity_active_ticks)},
      {"heartbeats_rate_limited", static_cast<double>(out.heartbeats_rate_limited)},
      {"datagrams_foreign_source", static_cast<double>(out.datagrams_foreign_source)},
      {"path_challenges_sent", static_cast<double>(out.path_challenges_sent)},
      {"samples_skipped", static_cast<double>(out.samples_skipped)},
      {"connections_open", static_cast<double>(out.connections_open)},
      {"connections_refused", static_cast<double>(out.connections_refused)},
  };
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(descriptor.field_count()));
  for (const auto& [name, value] : seen) {
    const google::protobuf::FieldDescriptor* field = descriptor.FindFieldByName(name);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(value, 100.0 + field->number()) << name;
  }
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
