// The SDK's translations: grpc::Status -> exception types, SDK values <-> haptic.v1 messages.
#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <string>
#include <typeinfo>
#include <utility>
#include <variant>
#include <vector>

#include "client_core.hpp"
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
                                 "api_version: client speaks 5, server speaks 6"),
                    "OpenSession");
    FAIL();
  } catch (const VersionMismatchError& error) {
    EXPECT_EQ(error.client_version(), kApiVersion);
    EXPECT_EQ(error.server_version(), 6u);
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

// Each orientation field comes back from its message as the spec that made it (GetScene reads
// fields back through the same from_proto), every impedance law included.
TEST(Conversions, OrientationFieldsRoundTrip) {
  for (const ImpedanceLaw law : {ImpedanceLaw::kVelocity, ImpedanceLaw::kBackwardDifference,
                                 ImpedanceLaw::kExactZoh, ImpedanceLaw::kTustin}) {
    const OrientationSpringSpec spring{.target = {0.5, 0.5, -0.5, 0.5}, .stiffness = 0.8,
                                       .damping = 0.02, .max_torque = 0.3, .law = law};
    const v1::Field message = to_proto(spring);
    ASSERT_TRUE(message.has_orientation_spring());
    EXPECT_EQ(message.orientation_spring().target().y(), -0.5);
    EXPECT_EQ(message.orientation_spring().stiffness(), 0.8);
    EXPECT_EQ(message.orientation_spring().max_torque(), 0.3);
    const SceneSpec::Field back = from_proto(message);
    ASSERT_TRUE(std::holds_alternative<OrientationSpringSpec>(back));
    EXPECT_EQ(std::get<OrientationSpringSpec>(back), spring);
  }

  const OrientationDetentSpec detent{.target = {0.0, 1.0, 0.0, 0.0}, .depth = 0.01, .radius = 0.2,
                                     .rim_height = 0.003, .rim_width = 0.1, .damping = 0.004};
  const v1::Field message = to_proto(detent);
  ASSERT_TRUE(message.has_orientation_detent());
  EXPECT_EQ(message.orientation_detent().target().x(), 1.0);
  EXPECT_EQ(message.orientation_detent().depth(), 0.01);
  EXPECT_EQ(message.orientation_detent().radius(), 0.2);
  EXPECT_EQ(message.orientation_detent().rim_height(), 0.003);
  EXPECT_EQ(message.orientation_detent().rim_width(), 0.1);
  EXPECT_EQ(message.orientation_detent().damping(), 0.004);
  const SceneSpec::Field back = from_proto(message);
  ASSERT_TRUE(std::holds_alternative<OrientationDetentSpec>(back));
  EXPECT_EQ(std::get<OrientationDetentSpec>(back), detent);

  // A target left unset (as a scene file may) is identity, not the message's all-zero default.
  v1::Field unset;
  unset.mutable_orientation_spring()->set_stiffness(1.0);
  EXPECT_EQ(std::get<OrientationSpringSpec>(from_proto(unset)).target, Quaternion{});
  unset.mutable_orientation_detent()->set_depth(1.0);
  EXPECT_EQ(std::get<OrientationDetentSpec>(from_proto(unset)).target, Quaternion{});
}

/// One default spec of each alternative of `Variant`, in order: a spec type added to SceneSpec is
/// covered without naming it here.
template <class Variant, std::size_t... I>
std::vector<Variant> one_of_each(std::index_sequence<I...>) {
  return {Variant(std::in_place_index<I>)...};
}
template <class Variant>
std::vector<Variant> one_of_each() {
  return one_of_each<Variant>(std::make_index_sequence<std::variant_size_v<Variant>>{});
}

/// `spec` with across_sites set to `across_sites` (and, where it has one, `shared` to the
/// opposite, so that swapping the two flags shows) goes to the wire with the flags and comes back
/// from it (GetScene's read-back) as the same spec.
template <class Spec>
void expect_flags_round_trip(Spec spec, bool across_sites) {
  SCOPED_TRACE(std::string(typeid(Spec).name()) + (across_sites ? " across sites" : " this site only"));
  spec.across_sites = across_sites;
  if constexpr (requires { spec.shared; }) spec.shared = !across_sites;
  const auto message = to_proto(spec);
  EXPECT_EQ(message.across_sites(), across_sites);
  if constexpr (requires { spec.shared; }) {
    EXPECT_EQ(message.shared(), !across_sites);
  }
  const auto back = from_proto(message);
  ASSERT_TRUE(std::holds_alternative<Spec>(back));
  EXPECT_EQ(std::get<Spec>(back), spec);
}

TEST(Conversions, AcrossSitesGoesToTheWireAndComesBackForEveryObjectAndFieldSpec) {
  for (const bool across_sites : {false, true}) {
    for (const SceneSpec::Object& object : one_of_each<SceneSpec::Object>()) {
      std::visit([&](const auto& spec) { expect_flags_round_trip(spec, across_sites); }, object);
    }
    for (const SceneSpec::Field& field : one_of_each<SceneSpec::Field>()) {
      std::visit([&](const auto& spec) { expect_flags_round_trip(spec, across_sites); }, field);
    }
  }
}

/// Sets every singular scalar field of `message` to 100 + its field number, whatever its type
/// (strings as that number's digits; an enum to its value 2; messages are left to the caller).
void fill_by_number(google::protobuf::Message& message) {
  const google::protobuf::Descriptor& descriptor = *message.GetDescriptor();
  const google::protobuf::Reflection& reflection = *message.GetReflection();
  for (int i = 0; i < descriptor.field_count(); ++i) {
    const google::protobuf::FieldDescriptor& field = *descriptor.field(i);
    if (field.is_repeated()) continue;
    const int value = 100 + field.number();
    switch (field.cpp_type()) {
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT64: reflection.SetUInt64(&message, &field, value); break;
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT32: reflection.SetUInt32(&message, &field, value); break;
      case google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE: reflection.SetDouble(&message, &field, value); break;
      case google::protobuf::FieldDescriptor::CPPTYPE_STRING:
        reflection.SetString(&message, &field, std::to_string(value));
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE: break;  // filled by the test itself
      case google::protobuf::FieldDescriptor::CPPTYPE_ENUM: reflection.SetEnumValue(&message, &field, 2); break;
      default:
        ADD_FAILURE() << descriptor.name() << "." << field.name() << " has a type this test does not set";
    }
  }
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
  s.set_buttons(5);
  EXPECT_FALSE(from_proto(s).orientation.has_value());  // a point device: neither
  EXPECT_FALSE(from_proto(s).torque.has_value());
  *s.mutable_orientation() = to_proto(Quaternion{0.5, -0.5, 0.5, -0.5});
  vec(s.mutable_torque(), 14.0, 15.0, 16.0);
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
  EXPECT_EQ(state.buttons, 5u);
  EXPECT_EQ(state.orientation, (Quaternion{0.5, -0.5, 0.5, -0.5}));
  EXPECT_EQ(state.torque, (Vec3{14.0, 15.0, 16.0}));
  // One line above per ToolState field: a new one without its line here fails the count.
  EXPECT_EQ(v1::ToolState::descriptor()->field_count(), 11);

  v1::Stats stats;
  const google::protobuf::Descriptor& descriptor = *v1::Stats::descriptor();
  // Field number n gets the value 100 + n, whatever its type (the one repeated field, clients,
  // gets one ClientStats filled the same way).
  fill_by_number(stats);
  v1::ClientStats& client = *stats.add_clients();
  fill_by_number(client);
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
      {"lateness_p999_us", out.lateness_p999_us},
      {"lateness_samples", static_cast<double>(out.lateness_samples)},
      {"window_s", out.window_s},
      {"send_delay_p999_us", out.send_delay_p999_us},
      {"connections_timed_out", static_cast<double>(out.connections_timed_out)},
      {"connections_evicted", static_cast<double>(out.connections_evicted)},
      {"tls_handshakes_failed", static_cast<double>(out.tls_handshakes_failed)},
      {"samples_missed", static_cast<double>(out.samples_missed)},
      {"ack_stalls", static_cast<double>(out.ack_stalls)},
  };
  // Every field but the repeated `clients` and the `federation` part, checked below.
  EXPECT_EQ(seen.size() + 2, static_cast<std::size_t>(descriptor.field_count()));
  for (const auto& [name, value] : seen) {
    const google::protobuf::FieldDescriptor* field = descriptor.FindFieldByName(name);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(value, 100.0 + field->number()) << name;
  }

  ASSERT_EQ(out.clients.size(), 1u);
  const ClientStats& c = out.clients[0];
  const google::protobuf::Descriptor& client_descriptor = *v1::ClientStats::descriptor();
  const std::vector<std::pair<const char*, double>> client_seen = {
      {"session_id", static_cast<double>(c.session_id)},
      {"client_name", std::stod(c.client_name)},
      {"peer", std::stod(c.peer)},
      {"device_index", static_cast<double>(c.device_index)},
      {"decimation", static_cast<double>(c.decimation)},
      {"datagrams_sent", static_cast<double>(c.datagrams_sent)},
      {"heartbeats", static_cast<double>(c.heartbeats)},
      {"states_received", static_cast<double>(c.states_received)},
      {"states_lost", static_cast<double>(c.states_lost)},
      {"last_heartbeat_age_s", c.last_heartbeat_age_s},
      {"round_trip_samples", static_cast<double>(c.round_trip_samples)},
      {"round_trip_p50_us", c.round_trip_p50_us},
      {"round_trip_p99_us", c.round_trip_p99_us},
      {"round_trip_p999_us", c.round_trip_p999_us},
      {"ack_window", static_cast<double>(c.ack_window)},
      {"acknowledged_sequence", static_cast<double>(c.acknowledged_sequence)},
      {"samples_unsent", static_cast<double>(c.samples_unsent)},
  };
  EXPECT_EQ(client_seen.size(), static_cast<std::size_t>(client_descriptor.field_count()));
  for (const auto& [name, value] : client_seen) {
    const google::protobuf::FieldDescriptor* field = client_descriptor.FindFieldByName(name);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(value, 100.0 + field->number()) << "ClientStats." << name;
  }
}

TEST(Conversions, TheFederationsStatsComeBackWholeAndOnlyWithAFederation) {
  v1::Stats stats;
  EXPECT_FALSE(from_proto(stats).federation.has_value());  // no federation section: none
  fill_by_number(*stats.mutable_federation());
  v1::CouplingStats& coupling = *stats.mutable_federation()->add_couplings();
  fill_by_number(coupling);  // kind: its value 2, MASS
  const Stats out = from_proto(stats);
  ASSERT_TRUE(out.federation.has_value());
  const FederationStats& f = *out.federation;
  const std::vector<std::pair<const char*, double>> seen = {
      {"samples_published", static_cast<double>(f.samples_published)},
      {"samples_failed", static_cast<double>(f.samples_failed)},
      {"items_published", static_cast<double>(f.items_published)},
      {"items_applied", static_cast<double>(f.items_applied)},
      {"items_refused", static_cast<double>(f.items_refused)},
      {"wrenches_accepted", static_cast<double>(f.wrenches_accepted)},
      {"wrenches_refused", static_cast<double>(f.wrenches_refused)},
      {"samples_refused", static_cast<double>(f.samples_refused)},
      {"energy_refused_j", f.energy_refused_j},
      {"sites_cut_off", static_cast<double>(f.sites_cut_off)},
  };
  const google::protobuf::Descriptor& descriptor = *v1::FederationStats::descriptor();
  EXPECT_EQ(seen.size() + 1, static_cast<std::size_t>(descriptor.field_count()));  // + couplings
  for (const auto& [name, value] : seen) {
    const google::protobuf::FieldDescriptor* field = descriptor.FindFieldByName(name);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(value, 100.0 + field->number()) << "FederationStats." << name;
  }
  ASSERT_EQ(f.couplings.size(), 1u);
  const CouplingStats& c = f.couplings[0];
  EXPECT_EQ(c.kind, CouplingStats::Kind::kMass);
  const std::vector<std::pair<const char*, double>> coupling_seen = {
      {"port", static_cast<double>(c.port)},         {"remote", static_cast<double>(c.remote)},
      {"mass", static_cast<double>(c.mass)},         {"injected_j", c.injected_j},
      {"given_j", c.given_j},                        {"sent_j", c.sent_j},
      {"received_j", c.received_j},                  {"reservoir_j", c.reservoir_j},
  };
  const google::protobuf::Descriptor& coupling_descriptor = *v1::CouplingStats::descriptor();
  EXPECT_EQ(coupling_seen.size() + 1, static_cast<std::size_t>(coupling_descriptor.field_count()));  // + kind
  for (const auto& [name, value] : coupling_seen) {
    const google::protobuf::FieldDescriptor* field = coupling_descriptor.FindFieldByName(name);
    ASSERT_NE(field, nullptr) << name;
    EXPECT_EQ(value, 100.0 + field->number()) << "CouplingStats." << name;
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

TEST(Client, ATokenIsNeverSentInClearToAnotherHostUnlessAllowed) {
  ClientConfig config;
  config.token = "controller-token-0123456789";
  // Not a loopback name, yet a connection to it would stay on this machine: should the check be
  // gone, the test fails with ConnectionError and sends nothing anywhere.
  config.server_address = "0.0.0.0:1";
  config.rpc_timeout = std::chrono::milliseconds(200);
  try {
    Client client(config);
    ADD_FAILURE() << "a token in clear to a non-loopback address was not refused";
  } catch (const InvalidArgumentError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("ClientConfig: token: would be sent in clear to '0.0.0.0:1'"), std::string::npos)
        << message;
    EXPECT_NE(message.find("TlsOptions"), std::string::npos) << message;
  }
  // A gRPC address list is loopback only if every member is: one that is not is refused (the
  // check looked at the first member alone). Should it pass, nothing leaves this machine.
  config.server_address = "ipv4:127.0.0.1:1,0.0.0.0:2";
  try {
    Client client(config);
    ADD_FAILURE() << "a token in clear to a list with a non-loopback address was not refused";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("would be sent in clear"), std::string::npos) << error.what();
  }
  config.server_address = "0.0.0.0:1";
  // The explicit opt-out passes this check (and says so on stderr): here the next check, an
  // invalid rpc_timeout, stops the client before any connection.
  config.allow_plaintext_token = true;
  config.rpc_timeout = std::chrono::milliseconds(0);
  ::testing::internal::CaptureStderr();
  try {
    Client client(config);
    ADD_FAILURE() << "an rpc_timeout of 0 was accepted";
  } catch (const InvalidArgumentError& error) {
    EXPECT_NE(std::string(error.what()).find("rpc_timeout"), std::string::npos) << error.what();
  }
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("sending the bearer token in clear to '0.0.0.0:1'"),
            std::string::npos);
}

TEST(Client, ATargetStaysOnThisHostOnlyWhenEveryAddressItNamesIsLoopback) {
  // Each form gRPC takes: a token may go in clear to these...
  for (const char* local : {"localhost:50051", "127.0.0.1:50051", "127.8.9.10:1", "[::1]:50051",
                            "[::ffff:127.0.0.1]:1", "dns:localhost:50051", "dns:///localhost:50051",
                            "dns:///127.0.0.1:50051", "ipv4:127.0.0.1:50051", "ipv6:[::1]:50051",
                            "ipv4:127.0.0.1:1,127.0.0.2:2", "ipv6:[::1]:1,[::ffff:127.0.0.1]:2",
                            "unix:/run/hapticd/control.sock", "unix:///run/hapticd/control.sock",
                            "unix-abstract:hapticd"}) {
    EXPECT_TRUE(stays_on_this_host(local)) << local;
  }
  // ...and to none of these: another host, a name whatever it resolves to, another resolver, a
  // list with one member elsewhere (the ipv6 list's first member alone was looked at before).
  for (const char* remote : {"0.0.0.0:1", "10.0.127.1:50051", "192.168.1.5:50051", "[fe80::1]:1",
                             "[::ffff:10.0.0.1]:1", "bench-a:50051", "127.example.com:50051",
                             "dns:bench-a:50051", "dns:///127.example.com:50051",
                             "dns://8.8.8.8/localhost:50051", "ipv4:127.0.0.1:1,10.0.0.2:2",
                             "ipv4:10.0.0.2:2,127.0.0.1:1", "ipv6:[::1]:1,[fe80::1]:2", "ipv4:127.0.0.1:1,",
                             "vsock:3:50051"}) {
    EXPECT_FALSE(stays_on_this_host(remote)) << remote;
  }
}

TEST(Client, UnreachableServerIsAConnectionError) {
  ClientConfig config;
  config.server_address = "127.0.0.1:1";
  config.rpc_timeout = std::chrono::milliseconds(200);
  EXPECT_THROW(Client{config}, ConnectionError);
}

// A server restart takes systemd's RestartSec (2 s) and a start: through the first 10 s of a loss
// the client tries at least every 100 ms, so it is back within a tenth of a second of the server
// being ready (the backoff used to double to 1 s within the first second).
TEST(Client, ALostClientRetriesEveryTenthOfASecondThroughARestartThenBacksOff) {
  using std::chrono::milliseconds;
  const ClientConfig config;  // reconnect_backoff_min 50 ms, reconnect_backoff_max 1 s
  milliseconds outage{0}, previous{0};
  std::vector<milliseconds> delays;
  while (outage < milliseconds(10'000)) {
    previous = next_reconnect_delay(previous, outage, config);
    delays.push_back(previous);
    outage += previous + milliseconds(5);  // each try itself takes a few ms (connection refused)
  }
  EXPECT_EQ(delays.front(), milliseconds(50));
  for (const milliseconds delay : delays) EXPECT_LE(delay, milliseconds(100));
  EXPECT_GT(delays.size(), 90u);  // about ten tries a second
  // Past the window: doubling to the configured maximum, and no further.
  for (int i = 0; i < 8; ++i) previous = next_reconnect_delay(previous, milliseconds(20'000), config);
  EXPECT_EQ(previous, milliseconds(1000));
  // A configured minimum above the fast period is kept: the user asked for calmer retries.
  ClientConfig calm;
  calm.reconnect_backoff_min = milliseconds(400);
  EXPECT_EQ(next_reconnect_delay(milliseconds(0), milliseconds(0), calm), milliseconds(400));
  EXPECT_EQ(next_reconnect_delay(milliseconds(400), milliseconds(500), calm), milliseconds(400));
}

}  // namespace
}  // namespace haptic::detail
