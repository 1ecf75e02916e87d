// The Client against an in-process fake of haptic.v1.Haptic on loopback: what it sends on the
// control plane, how it surfaces the fake's answers, and (with a plain UDP socket standing in for
// the server's data plane) its heartbeats and state reception.
#include <arpa/inet.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "haptic/haptic.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "haptic/wire/datagram.hpp"

namespace haptic {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr std::uint64_t kSessionId = 7;
constexpr wire::Key kKey = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
constexpr double kMaxStiffness = 1e5;  // the fake's limit. Unit: N/m.
constexpr std::uint32_t kLeaseTimeoutMs = 1000;
constexpr std::uint64_t kFirstSceneId = 100;  // ApplyScene numbers its items from here

// The fake's UDP data plane: a socket on 127.0.0.1 that learns the client's address from its
// heartbeats, as hapticd does.
class FakeDataPlane {
 public:
  FakeDataPlane() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof(address);
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
      ADD_FAILURE() << "cannot open the fake's UDP socket";
      return;
    }
    port_ = ntohs(address.sin_port);
    timeval timeout{1, 0};  // bounds a wait for a heartbeat that never comes
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  }
  ~FakeDataPlane() {
    if (fd_ >= 0) ::close(fd_);
  }
  FakeDataPlane(const FakeDataPlane&) = delete;
  FakeDataPlane& operator=(const FakeDataPlane&) = delete;

  std::uint16_t port() const { return port_; }

  /// Waits up to 1 s for an authenticated heartbeat; records it and where it came from.
  bool receive_heartbeat() {
    std::array<std::uint8_t, 2048> bytes{};
    sockaddr_in from{};
    socklen_t length = sizeof(from);
    const auto size = ::recvfrom(fd_, bytes.data(), bytes.size(), 0,
                                 reinterpret_cast<sockaddr*>(&from), &length);
    if (size <= 0) return false;
    wire::Header header;
    wire::HeartbeatPayload payload;
    if (wire::decode_heartbeat(std::span(bytes.data(), static_cast<std::size_t>(size)), kKey, header,
                               payload) != wire::DecodeError::kNone) {
      return false;
    }
    std::lock_guard lock(mutex_);
    client_ = from;
    heartbeats_.push_back(header);
    return true;
  }

  std::vector<wire::Header> heartbeats() const {
    std::lock_guard lock(mutex_);
    return heartbeats_;
  }

  void send_to_client(std::span<const std::uint8_t> bytes) {
    std::optional<sockaddr_in> to;
    {
      std::lock_guard lock(mutex_);
      to = client_;
    }
    ASSERT_TRUE(to) << "no heartbeat yet: the fake does not know where the client is";
    ASSERT_EQ(::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&*to),
                       sizeof(*to)),
              static_cast<ssize_t>(bytes.size()));
  }

  /// The next State datagram's sequence number (then counting on from it).
  void set_next_sequence(std::uint64_t sequence) { sequence_ = sequence - 1; }

  /// A State datagram for `tick` with tool height `z` (m), tagged with `key`.
  void send_state(std::uint64_t tick, double z, std::uint64_t session_id = kSessionId,
                  const wire::Key& key = kKey) {
    send_payload(state_at(tick, z), session_id, key);
  }

  /// The payload send_state sends: tool at height `z` (m), 1.5 N up, one contact.
  static wire::StatePayload state_at(std::uint64_t tick, double z) {
    wire::StatePayload state;
    state.tick = tick;
    state.p_WT = {0.0, 0.0, z};
    state.p_WP = state.p_WT;
    state.F_T_W = {0.0, 0.0, 1.5};
    state.contact_count = 1;
    return state;
  }

  /// `state` as a State datagram, or StateOriented when it has the orientation, stamped as a
  /// 1 kHz loop stamps its tick.
  void send_payload(const wire::StatePayload& state, std::uint64_t session_id = kSessionId,
                    const wire::Key& key = kKey) {
    wire::Header header;
    header.session_id = session_id;
    header.sequence = ++sequence_;
    header.time_ns = static_cast<std::int64_t>(state.tick) * 1'000'000;
    std::array<std::uint8_t, wire::kMaxDatagramSize> bytes{};
    const std::size_t size = wire::encode_state(header, state, key, bytes);
    ASSERT_EQ(size, state.has_orientation ? wire::kStateOrientedDatagramSize : wire::kStateDatagramSize);
    send_to_client(std::span<const std::uint8_t>(bytes.data(), size));
  }

 private:
  int fd_ = -1;
  std::uint16_t port_ = 0;
  std::uint64_t sequence_ = 0;
  mutable std::mutex mutex_;
  std::optional<sockaddr_in> client_;   // guarded by mutex_
  std::vector<wire::Header> heartbeats_;  // guarded by mutex_
};

// Answers what the tests need and records what it was asked.
class FakeHaptic final : public v1::Haptic::Service {
 public:
  explicit FakeHaptic(FakeDataPlane& data_plane) : data_plane_(data_plane) {}

  struct Record {
    std::string client_name;
    std::uint32_t api_version = 0;
    std::vector<v1::CreateObjectRequest> creates;
    std::vector<std::uint64_t> deleted;
    std::vector<std::uint64_t> fields_deleted;
    std::vector<v1::ApplySceneRequest> scenes;
    std::vector<std::uint32_t> decimations;
    bool closed = false;
  };
  Record record() const {
    std::lock_guard lock(mutex_);
    return record_;
  }
  void refuse_open_with(grpc::Status status) {
    std::lock_guard lock(mutex_);
    open_status_ = std::move(status);
  }

  grpc::Status OpenSession(grpc::ServerContext*, const v1::OpenSessionRequest* request,
                           v1::OpenSessionResponse* response) override {
    std::lock_guard lock(mutex_);
    record_.client_name = request->client_name();
    record_.api_version = request->api_version();
    if (!open_status_.ok()) return open_status_;
    response->set_session_id(kSessionId);
    response->set_udp_key(std::string(kKey.begin(), kKey.end()));
    response->set_udp_port(data_plane_.port());
    response->set_api_version(kApiVersion);
    response->mutable_device()->set_name("fake");
    response->mutable_device()->set_dof(3);
    response->mutable_device()->set_loop_rate_hz(1000.0);
    response->mutable_device()->set_simulated(true);
    response->set_lease_timeout_ms(kLeaseTimeoutMs);
    return grpc::Status::OK;
  }

  grpc::Status CloseSession(grpc::ServerContext*, const v1::SessionRef* request,
                            v1::Empty*) override {
    std::lock_guard lock(mutex_);
    if (request->session_id() != kSessionId) return {grpc::StatusCode::NOT_FOUND, "session_id"};
    record_.closed = true;
    return grpc::Status::OK;
  }

  grpc::Status CreateObject(grpc::ServerContext*, const v1::CreateObjectRequest* request,
                            v1::ItemRef* response) override {
    std::lock_guard lock(mutex_);
    record_.creates.push_back(*request);
    if (request->object().impedance().stiffness() > kMaxStiffness) {
      return {grpc::StatusCode::INVALID_ARGUMENT,
              "object.impedance.stiffness: must be <= 100000, got " +
                  std::to_string(request->object().impedance().stiffness())};
    }
    response->set_id(static_cast<std::uint64_t>(record_.creates.size()));
    return grpc::Status::OK;
  }

  grpc::Status DeleteObject(grpc::ServerContext*, const v1::DeleteRequest* request,
                            v1::Empty*) override {
    std::lock_guard lock(mutex_);
    record_.deleted.push_back(request->id());
    return grpc::Status::OK;
  }

  grpc::Status DeleteField(grpc::ServerContext*, const v1::DeleteRequest* request,
                           v1::Empty*) override {
    std::lock_guard lock(mutex_);
    record_.fields_deleted.push_back(request->id());
    return grpc::Status::OK;
  }

  // Numbers objects then fields from kFirstSceneId, as hapticd numbers them in request order.
  grpc::Status ApplyScene(grpc::ServerContext*, const v1::ApplySceneRequest* request,
                          v1::ApplySceneResponse* response) override {
    std::lock_guard lock(mutex_);
    record_.scenes.push_back(*request);
    std::uint64_t id = kFirstSceneId;
    for (int i = 0; i < request->scene().objects_size(); ++i) response->add_object_ids(id++);
    for (int i = 0; i < request->scene().fields_size(); ++i) response->add_field_ids(id++);
    return grpc::Status::OK;
  }

  grpc::Status SubscribeState(grpc::ServerContext*, const v1::SubscribeStateRequest* request,
                              v1::SubscribeStateResponse* response) override {
    {
      std::lock_guard lock(mutex_);
      record_.decimations.push_back(request->decimation());
    }
    response->set_udp_endpoint_known(data_plane_.receive_heartbeat());
    return grpc::Status::OK;
  }

 private:
  FakeDataPlane& data_plane_;
  mutable std::mutex mutex_;
  grpc::Status open_status_;  // guarded by mutex_
  Record record_;             // guarded by mutex_
};

class FakeServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(&service_);
    server_ = builder.BuildAndStart();
    ASSERT_TRUE(server_ != nullptr);
    ASSERT_GT(port, 0);
    config_.server_address = "127.0.0.1:" + std::to_string(port);
    config_.client_name = "fake-server-test";
    config_.state_decimation = 0;  // the tests that want state turn it on
  }
  void TearDown() override {
    if (server_) server_->Shutdown(std::chrono::system_clock::now() + seconds(1));
  }

  static WallSpec floor_wall(double stiffness) {
    return {.point = {0.0, 0.0, 0.01}, .normal = {0.0, 0.0, 1.0},
            .impedance = {.stiffness = stiffness, .damping = 1.0}};
  }

  FakeDataPlane data_plane_;
  FakeHaptic service_{data_plane_};
  std::unique_ptr<grpc::Server> server_;
  ClientConfig config_;
};

TEST_F(FakeServerTest, ConstructorOpensASessionAndDestructorClosesIt) {
  {
    Client client(config_);
    EXPECT_EQ(client.session_id(), kSessionId);
    EXPECT_EQ(client.device_info().name, "fake");
    EXPECT_EQ(client.device_info().loop_rate_hz, 1000.0);
    EXPECT_TRUE(client.device_info().simulated);
    EXPECT_EQ(client.lease_timeout(), milliseconds(kLeaseTimeoutMs));
    EXPECT_FALSE(service_.record().closed);
  }
  const auto record = service_.record();
  EXPECT_EQ(record.client_name, "fake-server-test");
  EXPECT_EQ(record.api_version, kApiVersion);
  EXPECT_TRUE(record.decimations.empty()) << "state_decimation 0 must not subscribe";
  EXPECT_TRUE(record.closed);
}

TEST_F(FakeServerTest, AddWallSendsAHalfSpaceAndTheHandleRemovesIt) {
  Client client(config_);
  {
    ObjectHandle wall = client.add_wall(floor_wall(1000.0));
    EXPECT_EQ(wall.id(), 1u);
    EXPECT_TRUE(wall.owned());
    const auto record = service_.record();
    ASSERT_EQ(record.creates.size(), 1u);
    const v1::CreateObjectRequest& sent = record.creates.front();
    EXPECT_EQ(sent.session_id(), kSessionId);
    ASSERT_TRUE(sent.object().has_half_space());
    EXPECT_EQ(sent.object().pose().position().z(), 0.01);
    EXPECT_EQ(sent.object().half_space().normal().z(), 1.0);
    EXPECT_EQ(sent.object().impedance().stiffness(), 1000.0);
    EXPECT_EQ(sent.object().impedance().damping(), 1.0);
    EXPECT_TRUE(record.deleted.empty());
  }
  EXPECT_EQ(service_.record().deleted, std::vector<std::uint64_t>{1u});

  ObjectHandle kept = client.add_wall(floor_wall(1000.0));
  EXPECT_EQ(kept.release(), 2u);
  EXPECT_FALSE(kept.owned());
  EXPECT_EQ(service_.record().deleted, std::vector<std::uint64_t>{1u}) << "release() detaches";
}

TEST_F(FakeServerTest, ServersInvalidArgumentBecomesInvalidArgumentErrorWithItsMessage) {
  Client client(config_);
  try {
    client.add_wall(floor_wall(1e6));
    FAIL() << "no exception";
  } catch (const InvalidArgumentError& error) {
    EXPECT_EQ(error.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(std::string(error.what()).rfind("CreateObject: object.impedance.stiffness: must be <= 100000", 0),
              0u)
        << error.what();
  }
}

/// The message of the haptic::Error `action` throws ("" if none).
template <typename Action>
std::string error_of(Action&& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return {};
}

// Every error names the call first and then the field by the server's path for it, the same
// whichever side found the mistake: "CreateObject: object.impedance.stiffness: ...".
TEST_F(FakeServerTest, ObviousMistakesAreCaughtBeforeTheServerIsAskedNamingCallAndField) {
  Client client(config_);
  EXPECT_EQ(error_of([&] { client.add_wall(floor_wall(-1.0)); }),
            "CreateObject: object.impedance.stiffness: must be >= 0");
  EXPECT_EQ(error_of([&] { client.add_wall({.normal = {0.0, 0.0, 0.0}}); }),
            "CreateObject: object.half_space.normal: must be non-zero");
  EXPECT_EQ(error_of([&] { client.add_sphere({.radius = 0.0}); }),
            "CreateObject: object.sphere.radius: must be > 0");
  EXPECT_EQ(error_of([&] { client.add_spring_field({.stiffness = -2.0}); }),
            "CreateField: field.spring_to_point.stiffness: must be >= 0");
  EXPECT_EQ(error_of([&] {
              client.set_operator(OperatorInput::follow({std::nan(""), 0, 0}, 100.0, 1.0));
            }),
            "SetOperator: input.target.x: must be finite");
  EXPECT_TRUE(service_.record().creates.empty());
  ObjectHandle wall = client.add_wall(floor_wall(1000.0));
  EXPECT_EQ(error_of([&] { wall.update(WallSpec{.impedance = {1000.0, -1.0}}); }),
            "UpdateObject: object.impedance.damping: must be >= 0");
  ClientConfig bad = config_;
  bad.rpc_timeout = std::chrono::milliseconds(0);
  EXPECT_EQ(error_of([&] { Client refused(bad); }), "ClientConfig: rpc_timeout: must be positive");
  Client moved_to = std::move(client);
  EXPECT_EQ(error_of([&] { (void)client.stats(); }), "GetStats: the Client was moved from or closed");
  EXPECT_EQ(error_of([&] { (void)client.session_id(); }), "session_id: the Client was moved from or closed");
}

TEST_F(FakeServerTest, ApplySceneSendsWallsThenSpheresAndStalesEarlierHandles) {
  Client client(config_);
  ObjectHandle before = client.add_wall(floor_wall(1000.0));
  SceneHandles scene = client.apply_scene(
      {floor_wall(500.0)}, {{.center = {0.0, 0.0, 0.05}, .radius = 0.02, .impedance = {300.0, 0.5}}},
      {{.anchor = {0.0, 0.0, 0.02}, .stiffness = 20.0, .max_force = 2.0}});

  const auto record = service_.record();
  ASSERT_EQ(record.scenes.size(), 1u);
  const v1::Scene& sent = record.scenes.front().scene();
  EXPECT_EQ(record.scenes.front().session_id(), kSessionId);
  ASSERT_EQ(sent.objects_size(), 2);
  EXPECT_TRUE(sent.objects(0).has_half_space());
  EXPECT_EQ(sent.objects(0).impedance().stiffness(), 500.0);
  EXPECT_EQ(sent.objects(1).sphere().radius(), 0.02);
  ASSERT_EQ(sent.fields_size(), 1);
  EXPECT_EQ(sent.fields(0).spring_to_point().max_force(), 2.0);

  ASSERT_EQ(scene.walls.size(), 1u);
  ASSERT_EQ(scene.spheres.size(), 1u);
  ASSERT_EQ(scene.springs.size(), 1u);
  EXPECT_EQ(scene.walls[0].id(), kFirstSceneId);
  EXPECT_EQ(scene.spheres[0].id(), kFirstSceneId + 1);
  EXPECT_EQ(scene.springs[0].id(), kFirstSceneId + 2);

  // The scene replaced the earlier wall on the server: its handle neither updates nor removes.
  EXPECT_THROW(before.update(floor_wall(10.0)), NotFoundError);
  EXPECT_NO_THROW(before.remove());
  EXPECT_TRUE(service_.record().deleted.empty());

  scene.walls[0].remove();
  scene.springs.clear();
  EXPECT_EQ(service_.record().deleted, std::vector<std::uint64_t>{kFirstSceneId});
  EXPECT_EQ(service_.record().fields_deleted, std::vector<std::uint64_t>{kFirstSceneId + 2});
}

TEST_F(FakeServerTest, OrientationFieldsGoOutAsTheirOwnKinds) {
  Client client(config_);
  SceneSpec scene;
  scene.fields.push_back(OrientationSpringSpec{.target = {0.0, 0.0, 1.0, 0.0}, .stiffness = 0.5,
                                               .damping = 0.01, .max_torque = 0.2,
                                               .law = ImpedanceLaw::kExactZoh});
  scene.fields.push_back(OrientationDetentSpec{.depth = 0.01, .radius = 0.2, .rim_height = 0.002,
                                               .rim_width = 0.1, .damping = 0.001});
  const AppliedScene applied = client.apply_scene(scene);
  ASSERT_EQ(applied.fields.size(), 2u);

  const auto record = service_.record();
  ASSERT_EQ(record.scenes.size(), 1u);
  const v1::Scene& sent = record.scenes.front().scene();
  ASSERT_EQ(sent.fields_size(), 2);
  ASSERT_TRUE(sent.fields(0).has_orientation_spring());
  EXPECT_EQ(sent.fields(0).orientation_spring().target().y(), 1.0);
  EXPECT_EQ(sent.fields(0).orientation_spring().max_torque(), 0.2);
  EXPECT_EQ(sent.fields(0).orientation_spring().law(), v1::Impedance::EXACT_ZOH);
  ASSERT_TRUE(sent.fields(1).has_orientation_detent());
  EXPECT_EQ(sent.fields(1).orientation_detent().target().w(), 1.0);  // identity by default
  EXPECT_EQ(sent.fields(1).orientation_detent().rim_width(), 0.1);
}

TEST_F(FakeServerTest, ApplySceneNamesTheBadSpecAndSendsNothing) {
  Client client(config_);
  try {
    client.apply_scene({floor_wall(1000.0), floor_wall(-5.0)}, {}, {});
    FAIL() << "no exception";
  } catch (const InvalidArgumentError& error) {
    EXPECT_EQ(std::string(error.what()), "ApplyScene: scene.objects[1].impedance.stiffness: must be >= 0");
  }
  EXPECT_TRUE(service_.record().scenes.empty());
}

TEST_F(FakeServerTest, AnotherApiVersionIsAVersionMismatchCarryingBoth) {
  service_.refuse_open_with({grpc::StatusCode::FAILED_PRECONDITION,
                             "api_version: client speaks 5, server speaks 6"});
  try {
    Client client(config_);
    FAIL() << "no exception";
  } catch (const VersionMismatchError& error) {
    EXPECT_EQ(error.client_version(), kApiVersion);
    EXPECT_EQ(error.client_version(), 5u);
    EXPECT_EQ(error.server_version(), 6u);
  }
}

TEST_F(FakeServerTest, AHandleThatOutlivesItsClientIsHarmless) {
  ObjectHandle wall;
  {
    Client client(config_);
    wall = client.add_wall(floor_wall(1000.0));
  }
  EXPECT_TRUE(service_.record().closed);
  EXPECT_NO_THROW(wall.remove());
  EXPECT_TRUE(service_.record().deleted.empty()) << "the session, and the wall with it, is gone";
}

TEST_F(FakeServerTest, HeartbeatsTellTheServerWhereToSendStateAndBadDatagramsAreCounted) {
  config_.state_decimation = 1;
  Client client(config_);  // subscribes: returns once a heartbeat has reached the fake
  const auto heartbeats = data_plane_.heartbeats();
  ASSERT_FALSE(heartbeats.empty());
  EXPECT_EQ(heartbeats.front().session_id, kSessionId);
  EXPECT_EQ(heartbeats.front().sequence, 1u);
  EXPECT_EQ(service_.record().decimations.back(), 1u);

  // One socket, one receive thread: the datagrams are handled in the order sent.
  const std::array<std::uint8_t, wire::kStateDatagramSize> garbage{};
  data_plane_.send_to_client(garbage);
  data_plane_.send_state(5, 0.004);
  State state;
  ASSERT_TRUE(client.wait_for_tick(5, state, seconds(2)));
  EXPECT_EQ(state.tick, 5u);
  EXPECT_EQ(state.sequence, 1u);
  EXPECT_DOUBLE_EQ(state.server_time, 0.005);
  EXPECT_EQ(state.position.z, 0.004);
  EXPECT_EQ(state.force.z, 1.5);
  EXPECT_EQ(state.contact_count, 1u);
  EXPECT_FALSE(client.poll_state(state, milliseconds(0))) << "nothing newer than tick 5";

  wire::Key wrong_key = kKey;
  wrong_key[0] ^= 1;
  data_plane_.send_state(6, 0.0, kSessionId, wrong_key);
  data_plane_.send_state(7, 0.0, kSessionId + 1);
  data_plane_.send_state(8, 0.003);
  ASSERT_TRUE(client.poll_state(state, seconds(2)));
  EXPECT_EQ(state.tick, 8u);
  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.accepted, 2u);
  EXPECT_EQ(counters.rejected, 3u);
  EXPECT_TRUE(client.clock_offset().has_value());
}

TEST_F(FakeServerTest, GapsInTheSequenceAreLostSamplesAndLateOnesAreReordered) {
  config_.state_decimation = 1;
  Client client(config_);
  ASSERT_TRUE(data_plane_.receive_heartbeat());
  State state;
  data_plane_.send_state(1, 0.0);  // sequences 1, 2
  data_plane_.send_state(2, 0.0);
  data_plane_.set_next_sequence(6);  // 3, 4 and 5 lost on the way
  data_plane_.send_state(6, 0.0);
  ASSERT_TRUE(client.wait_for_tick(6, state, seconds(2)));
  EXPECT_EQ(client.receive_counters().lost, 3u);
  data_plane_.set_next_sequence(4);  // 4 was late, not lost
  data_plane_.send_state(4, 0.0);
  data_plane_.set_next_sequence(1);  // a new subscription numbers from 1 again, with newer ticks
  data_plane_.send_state(10, 0.0);
  data_plane_.send_state(11, 0.0);
  ASSERT_TRUE(client.wait_for_tick(11, state, seconds(2)));
  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.lost, 2u);
  EXPECT_EQ(counters.reordered, 1u);
  EXPECT_EQ(counters.accepted, 6u);
  EXPECT_EQ(counters.reconnects, 0u);
}

TEST_F(FakeServerTest, CloseFromInsideACallbackIsRefusedAndTheClientClosesAfter) {
  config_.state_decimation = 1;
  Client client(config_);
  ASSERT_TRUE(data_plane_.receive_heartbeat());
  std::mutex mutex;
  std::condition_variable done;
  std::string refused;
  client.on_state([&](const State&) {
    std::string message = error_of([&] { client.close(); });
    std::lock_guard lock(mutex);
    if (refused.empty()) refused = message.empty() ? "no error" : message;
    done.notify_all();
  });
  data_plane_.send_state(1, 0.0);
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(done.wait_for(lock, seconds(2), [&] { return !refused.empty(); }));
  }
  EXPECT_EQ(refused.rfind("close: called from inside one of this client's callbacks", 0), 0u) << refused;
  client.on_state({});
  EXPECT_NO_THROW(client.close());  // from the test's own thread, it closes
  EXPECT_EQ(error_of([&] { (void)client.stats(); }), "GetStats: the Client was moved from or closed");
}

TEST_F(FakeServerTest, ADuplicatedStateIsDroppedNotCountedAsLateOrLost) {
  config_.state_decimation = 1;
  Client client(config_);
  ASSERT_TRUE(data_plane_.receive_heartbeat());
  State state;
  data_plane_.send_state(1, 0.0);
  data_plane_.set_next_sequence(3);  // 2 lost
  data_plane_.send_state(3, 0.0);
  data_plane_.set_next_sequence(3);  // 3 again, at once
  data_plane_.send_state(3, 0.0);
  data_plane_.set_next_sequence(2);  // 2 late: not lost after all
  data_plane_.send_state(2, 0.0);
  data_plane_.set_next_sequence(2);  // and 2 again, later still
  data_plane_.send_state(2, 0.0);
  data_plane_.set_next_sequence(1);  // 1 again, after newer ones
  data_plane_.send_state(1, 0.0);
  data_plane_.set_next_sequence(4);
  data_plane_.send_state(4, 0.0);
  ASSERT_TRUE(client.wait_for_tick(4, state, seconds(2)));
  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.duplicates, 3u);
  EXPECT_EQ(counters.accepted, 4u);  // 1, 3, 2, 4
  EXPECT_EQ(counters.reordered, 1u);
  EXPECT_EQ(counters.lost, 0u);
}

TEST_F(FakeServerTest, TheClockOffsetLiesBetweenTheSendAndTheReceiptOfASample) {
  config_.state_decimation = 1;
  Client client(config_);
  EXPECT_FALSE(client.clock_offset().has_value());  // nothing received yet
  const auto sent_after = std::chrono::steady_clock::now();
  data_plane_.send_state(1000, 0.0);  // stamped 1.000 s of server time
  State state;
  ASSERT_TRUE(client.wait_for_tick(1000, state, seconds(2)));
  const auto received_before = std::chrono::steady_clock::now();
  ASSERT_TRUE(client.clock_offset().has_value());
  // server − local at receipt, the receipt falling between the two readings above.
  const std::chrono::nanoseconds server = seconds(1);
  EXPECT_LE(*client.clock_offset(), server - sent_after.time_since_epoch());
  EXPECT_GE(*client.clock_offset(), server - received_before.time_since_epoch());
  // With no drift known yet, the server's time at a local moment is that moment plus the offset:
  // at the receipt it reads the sample's stamp, 1 s, to within the receipt's uncertainty.
  EXPECT_FALSE(client.clock_drift().has_value());
  const std::optional<double> at_receipt = client.server_time_at(received_before);
  ASSERT_TRUE(at_receipt.has_value());
  EXPECT_GE(*at_receipt, 1.0);
  EXPECT_LE(*at_receipt, 1.0 + std::chrono::duration<double>(received_before - sent_after).count());
}

TEST_F(FakeServerTest, ABacklogIsDrainedAndOnlyItsNewestSampleIsHandedOut) {
  config_.state_decimation = 1;
  Client client(config_);
  // The application's callback is slow: while it holds the first sample, 50 more arrive.
  std::mutex mutex;
  std::condition_variable changed;
  bool release = false;
  std::vector<State> delivered;
  client.on_state([&](const State& state) {
    std::unique_lock lock(mutex);
    delivered.push_back(state);
    changed.notify_all();
    changed.wait_for(lock, seconds(5), [&] { return release; });
  });
  data_plane_.send_state(1, 0.0);
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(changed.wait_for(lock, seconds(5), [&] { return !delivered.empty(); }));
  }
  for (std::uint64_t tick = 2; tick <= 51; ++tick) data_plane_.send_state(tick, 0.001 * tick);
  // The receive thread takes them all while the callback is held (sent is not yet read: releasing
  // earlier would hand the callback one from the middle too).
  const auto give_up = std::chrono::steady_clock::now() + seconds(5);
  while (client.receive_counters().accepted < 51 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(milliseconds(1));
  }
  {
    std::lock_guard lock(mutex);
    release = true;
  }
  changed.notify_all();
  {
    // One more call, with the newest: the 49 in between were read and dropped, not queued.
    std::unique_lock lock(mutex);
    ASSERT_TRUE(changed.wait_for(lock, seconds(5), [&] { return delivered.size() >= 2; }));
  }
  State newest;
  ASSERT_TRUE(client.wait_for_tick(51, newest, seconds(5)));
  client.on_state({});
  std::lock_guard lock(mutex);
  ASSERT_EQ(delivered.size(), 2u);
  EXPECT_EQ(delivered[1].tick, 51u);
  EXPECT_DOUBLE_EQ(delivered[1].position.z, 0.051);
  const ReceiveCounters counters = client.receive_counters();
  EXPECT_EQ(counters.accepted, 51u);
  // The receive thread is not held up by the callback any more: the 49 are passed over partly on
  // the socket (skipped) and partly at the hand-off to the callback's thread (callback_skipped).
  EXPECT_EQ(counters.skipped + counters.callback_skipped, 49u);
}

TEST_F(FakeServerTest, ASamplesAgeIsHowMuchLongerItTookThanTheQuickestRecentOne) {
  config_.state_decimation = 1;
  Client client(config_);
  data_plane_.send_state(100, 0.0);  // stamped 100 ms: the reference
  State state;
  ASSERT_TRUE(client.wait_for_tick(100, state, seconds(2)));
  EXPECT_EQ(state.age, std::chrono::nanoseconds(0));
  // Stamped 1 ms later, but held 30 ms on the way (as if queued): about 29 ms old.
  std::this_thread::sleep_for(milliseconds(30));
  data_plane_.send_state(101, 0.0);
  ASSERT_TRUE(client.wait_for_tick(101, state, seconds(2)));
  EXPECT_GE(state.age, milliseconds(29));
  EXPECT_LT(state.age, seconds(2));
}

// A device that measures the orientation streams StateOriented: State gets the orientation and
// the torque together; a plain State has neither.
TEST_F(FakeServerTest, AnOrientedSampleCarriesTheOrientationAndTheTorque) {
  config_.state_decimation = 1;
  Client client(config_);
  wire::StatePayload oriented = FakeDataPlane::state_at(1, 0.002);
  oriented.has_orientation = true;
  oriented.R_WT = {0.5, 0.5, -0.5, 0.5};
  oriented.tau_T_W = {0.0, 0.25, -1.0};
  data_plane_.send_payload(oriented);
  State state;
  ASSERT_TRUE(client.wait_for_tick(1, state, seconds(2)));
  ASSERT_TRUE(state.orientation.has_value());
  EXPECT_EQ(*state.orientation, (Quaternion{0.5, 0.5, -0.5, 0.5}));
  ASSERT_TRUE(state.torque.has_value());
  EXPECT_EQ(*state.torque, (Vec3{0.0, 0.25, -1.0}));
  EXPECT_EQ(state.position.z, 0.002);

  data_plane_.send_state(2, 0.0);
  ASSERT_TRUE(client.wait_for_tick(2, state, seconds(2)));
  EXPECT_FALSE(state.orientation.has_value());
  EXPECT_FALSE(state.torque.has_value());
}

TEST_F(FakeServerTest, PollReturnsTheFirstSampleEvenAtTickZero) {
  config_.state_decimation = 1;
  Client client(config_);
  data_plane_.send_state(0, 0.01);
  State state;
  ASSERT_TRUE(client.poll_state(state, seconds(2)));
  EXPECT_EQ(state.tick, 0u);
  EXPECT_FALSE(client.poll_state(state, milliseconds(0)));
}

}  // namespace
}  // namespace haptic
