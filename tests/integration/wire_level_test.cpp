// The server seen from the wire, without the SDK: raw gRPC calls and raw UDP datagrams. Bad input
// gets a named error and is dropped and counted; the server keeps serving.
#include <arpa/inet.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "haptic/wire/datagram.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

class WireLevel : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<test::ServerProcess>(test::lockstep_config());
    stub_ = v1::Haptic::NewStub(
        grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials()));
    v1::OpenSessionRequest request;
    request.set_client_name("wire-test");
    request.set_api_version(v1::API_VERSION_CURRENT);
    ASSERT_TRUE(call(&v1::Haptic::Stub::OpenSession, request, session_).ok());
    std::copy(session_.udp_key().begin(), session_.udp_key().end(), key_.begin());
    socket_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in local{};
    local.sin_family = AF_INET;
    local.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::bind(socket_, reinterpret_cast<sockaddr*>(&local), sizeof local), 0);
    timeval timeout{2, 0};
    ::setsockopt(socket_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    server_udp_.sin_family = AF_INET;
    server_udp_.sin_port = htons(static_cast<std::uint16_t>(session_.udp_port()));
    server_udp_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  void TearDown() override {
    if (socket_ >= 0) ::close(socket_);
  }

  /// One unary call carrying a session secret: by default this fixture's session's.
  template <typename Method, typename Request, typename Response>
  grpc::Status call(Method method, const Request& request, Response& response,
                    const std::string* secret = nullptr) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    const std::string& own = secret ? *secret : session_.session_secret();
    if (!own.empty()) context.AddMetadata(io::kSessionSecretMetadataKey, own);
    return ((*stub_).*method)(&context, request, &response);
  }

  void send(const std::vector<std::uint8_t>& bytes) {
    ::sendto(socket_, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&server_udp_),
             sizeof server_udp_);
  }

  std::vector<std::uint8_t> heartbeat(std::uint64_t sequence, const wire::Key& key) {
    std::vector<std::uint8_t> bytes(wire::kHeartbeatDatagramSize);
    wire::Header header;
    header.session_id = session_.session_id();
    header.sequence = sequence;
    wire::encode_heartbeat(header, wire::HeartbeatPayload{}, key, bytes);
    return bytes;
  }

  /// Receives the PathChallenge the server sends a new address and echoes its nonce with
  /// sequence `sequence`, from the same socket.
  void answer_challenge(std::uint64_t sequence) {
    std::array<std::uint8_t, 512> buffer{};
    const ssize_t n = ::recv(socket_, buffer.data(), buffer.size(), 0);
    ASSERT_EQ(n, static_cast<ssize_t>(wire::kPathDatagramSize));
    wire::Header h;
    wire::PathChallengePayload challenge;
    ASSERT_EQ(wire::decode_path_challenge(std::span(buffer.data(), static_cast<std::size_t>(n)),
                                          key_, h, challenge),
              wire::DecodeError::kNone);
    std::vector<std::uint8_t> bytes(wire::kPathDatagramSize);
    wire::Header header;
    header.session_id = session_.session_id();
    header.sequence = sequence;
    wire::encode_path_response(header, {challenge.nonce, 0}, key_, bytes);
    send(bytes);
  }

  v1::Stats stats() {
    v1::SessionRef ref;
    ref.set_session_id(session_.session_id());
    v1::Stats out;
    EXPECT_TRUE(call(&v1::Haptic::Stub::GetStats, ref, out).ok());
    return out;
  }

  /// Waits (bounded) until the server has accounted for `received` heartbeats and `dropped` drops.
  v1::Stats wait_for_counts(std::uint64_t received, std::uint64_t dropped) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    v1::Stats s = stats();
    while ((s.datagrams_received() < received || s.datagrams_dropped() < dropped) &&
           std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      s = stats();
    }
    return s;
  }

  std::unique_ptr<test::ServerProcess> server_;
  std::unique_ptr<v1::Haptic::Stub> stub_;
  v1::OpenSessionResponse session_;
  wire::Key key_{};
  int socket_ = -1;
  sockaddr_in server_udp_{};
};

TEST_F(WireLevel, BadDatagramsAreDroppedAndCountedAndTheServerCarriesOn) {
  send(heartbeat(1, key_));
  ASSERT_EQ(wait_for_counts(1, 0).datagrams_received(), 1u);

  auto good = heartbeat(2, key_);
  std::vector<std::vector<std::uint8_t>> bad;
  bad.push_back({});                                             // empty
  bad.push_back(std::vector<std::uint8_t>(good.begin(), good.begin() + 30));  // truncated
  auto wrong_version = good;
  wrong_version[4] = 99;
  bad.push_back(wrong_version);
  auto flipped = good;
  flipped[45] ^= 0x10;  // payload changed: the tag no longer matches
  bad.push_back(flipped);
  wire::Key wrong_key = key_;
  wrong_key[3] ^= 0xff;
  bad.push_back(heartbeat(3, wrong_key));
  bad.push_back(heartbeat(1, key_));  // replayed sequence
  std::vector<std::uint8_t> unknown_session(wire::kHeartbeatDatagramSize);
  wire::Header header;
  header.session_id = session_.session_id() ^ 1;
  header.sequence = 10;
  wire::encode_heartbeat(header, {}, key_, unknown_session);
  bad.push_back(unknown_session);
  for (const auto& bytes : bad) send(bytes);

  const v1::Stats after = wait_for_counts(1, bad.size());
  EXPECT_EQ(after.datagrams_dropped(), bad.size());  // every one, the empty datagram included
  EXPECT_EQ(after.datagrams_received(), 1u);
  // Still serving: a good heartbeat is accepted after all that.
  send(heartbeat(4, key_));
  EXPECT_EQ(wait_for_counts(2, 0).datagrams_received(), 2u);
}

TEST_F(WireLevel, StateArrivesAtTheHeartbeatAddressOnlyWhenSubscribed) {
  send(heartbeat(1, key_));
  ASSERT_EQ(wait_for_counts(1, 0).datagrams_received(), 1u);
  answer_challenge(2);  // the address proves it receives: from here on state may go there
  ASSERT_EQ(wait_for_counts(2, 0).datagrams_received(), 2u);
  v1::StepRequest step;
  step.set_session_id(session_.session_id());
  step.set_ticks(5);
  v1::StepResponse stepped;
  ASSERT_TRUE(call(&v1::Haptic::Stub::Step, step, stepped).ok());
  EXPECT_EQ(stats().datagrams_sent(), 0u);  // nobody subscribed: nothing encoded or sent

  v1::SubscribeStateRequest subscribe;
  subscribe.set_session_id(session_.session_id());
  subscribe.set_decimation(2);
  v1::SubscribeStateResponse subscribed;
  ASSERT_TRUE(call(&v1::Haptic::Stub::SubscribeState, subscribe, subscribed).ok());
  EXPECT_TRUE(subscribed.udp_endpoint_known());
  step.set_ticks(4);  // ticks 6..9: decimation 2 sends ticks 6 and 8
  ASSERT_TRUE(call(&v1::Haptic::Stub::Step, step, stepped).ok());
  EXPECT_EQ(stepped.tick(), 9u);

  std::array<std::uint8_t, 512> buffer{};
  std::vector<std::uint64_t> ticks;
  for (int i = 0; i < 2; ++i) {
    const ssize_t n = ::recv(socket_, buffer.data(), buffer.size(), 0);
    ASSERT_GT(n, 0);
    wire::Header h;
    wire::StatePayload state;
    ASSERT_EQ(wire::decode_state(std::span(buffer.data(), static_cast<std::size_t>(n)), key_, h, state),
              wire::DecodeError::kNone);
    EXPECT_EQ(h.session_id, session_.session_id());
    EXPECT_EQ(h.time_ns, static_cast<std::int64_t>(state.tick - 1) * 1'000'000);  // lockstep time
    ticks.push_back(state.tick);
  }
  EXPECT_EQ(ticks, (std::vector<std::uint64_t>{6, 8}));
}

TEST_F(WireLevel, InvalidRequestsNameTheFieldAndChangeNothing) {
  v1::ApplySceneRequest request;
  request.set_session_id(session_.session_id());
  auto* wall = request.mutable_scene()->add_objects();
  wall->mutable_impedance()->set_stiffness(1000.0);
  wall->mutable_half_space()->mutable_normal()->set_z(1.0);
  auto* broken = request.mutable_scene()->add_objects();
  broken->mutable_impedance()->set_stiffness(std::numeric_limits<double>::quiet_NaN());
  broken->mutable_sphere()->set_radius(0.01);
  v1::ApplySceneResponse response;
  const grpc::Status status = call(&v1::Haptic::Stub::ApplyScene, request, response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().rfind("scene.objects[1].impedance.stiffness:", 0), 0u)
      << status.error_message();
  EXPECT_EQ(stats().objects(), 0u);  // the good wall was not applied either

  v1::OpenSessionRequest old_client;
  old_client.set_client_name("old");
  old_client.set_api_version(7);
  v1::OpenSessionResponse ignored;
  const grpc::Status mismatch = call(&v1::Haptic::Stub::OpenSession, old_client, ignored);
  EXPECT_EQ(mismatch.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(mismatch.error_message(), "api_version: client speaks 7, server speaks 5");

  v1::StepRequest step;
  step.set_session_id(session_.session_id());
  step.set_ticks(0);
  v1::StepResponse stepped;
  EXPECT_EQ(call(&v1::Haptic::Stub::Step, step, stepped).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  v1::SessionRef nobody;
  nobody.set_session_id(12345);
  v1::Stats s;
  EXPECT_EQ(call(&v1::Haptic::Stub::GetStats, nobody, s).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(WireLevel, EventsStreamReportsOtherSessionsOpeningAndClosing) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  context.AddMetadata(io::kSessionSecretMetadataKey, session_.session_secret());
  v1::WatchEventsRequest watch;
  watch.set_session_id(session_.session_id());
  auto reader = stub_->WatchEvents(&context, watch);
  v1::Event event;
  ASSERT_TRUE(reader->Read(&event));
  ASSERT_EQ(event.kind(), v1::Event::WATCH_STARTED);  // from here on nothing is missed

  v1::OpenSessionRequest open;
  open.set_client_name("second");
  open.set_api_version(v1::API_VERSION_CURRENT);
  v1::OpenSessionResponse second;
  ASSERT_TRUE(call(&v1::Haptic::Stub::OpenSession, open, second).ok());
  v1::SessionRef close;
  close.set_session_id(second.session_id());
  v1::Empty empty;
  ASSERT_TRUE(call(&v1::Haptic::Stub::CloseSession, close, empty, &second.session_secret()).ok());

  ASSERT_TRUE(reader->Read(&event));
  EXPECT_EQ(event.kind(), v1::Event::SESSION_OPENED);
  EXPECT_EQ(event.session_id(), second.session_id());
  EXPECT_NE(event.message().find("second"), std::string::npos);
  ASSERT_TRUE(reader->Read(&event));
  EXPECT_EQ(event.kind(), v1::Event::SESSION_CLOSED);
  EXPECT_EQ(event.session_id(), second.session_id());
  context.TryCancel();
}

TEST_F(WireLevel, AnotherSessionsObjectIsPermissionDenied) {
  v1::CreateObjectRequest create;
  create.set_session_id(session_.session_id());
  create.mutable_object()->mutable_impedance()->set_stiffness(100.0);
  create.mutable_object()->mutable_sphere()->set_radius(0.01);
  v1::ItemRef item;
  ASSERT_TRUE(call(&v1::Haptic::Stub::CreateObject, create, item).ok());

  v1::OpenSessionRequest open;
  open.set_client_name("intruder");
  open.set_api_version(v1::API_VERSION_CURRENT);
  v1::OpenSessionResponse intruder;
  ASSERT_TRUE(call(&v1::Haptic::Stub::OpenSession, open, intruder).ok());
  v1::DeleteRequest remove;
  remove.set_session_id(intruder.session_id());
  remove.set_id(item.id());
  v1::Empty empty;
  const grpc::Status status =
      call(&v1::Haptic::Stub::DeleteObject, remove, empty, &intruder.session_secret());
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(stats().objects(), 1u);
}

/// A UDP socket bound to `ip` (any port) with a short receive timeout: a bystander on the LAN.
int bystander_socket(const char* ip) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  ::inet_pton(AF_INET, ip, &local.sin_addr);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&local), sizeof local) != 0) {
    ::close(fd);
    return -1;
  }
  timeval timeout{0, 300'000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  return fd;
}

TEST_F(WireLevel, ASpoofedSourceGetsNoStateAndNothingLargerThanWhatWasSent) {
  // The client subscribes, then sends its own signed heartbeats with a bystander's source
  // address, as a spoofer on the LAN could: one on this host, one on another (127.0.0.2).
  v1::SubscribeStateRequest subscribe;
  subscribe.set_session_id(session_.session_id());
  subscribe.set_decimation(1);
  v1::SubscribeStateResponse subscribed;
  ASSERT_TRUE(call(&v1::Haptic::Stub::SubscribeState, subscribe, subscribed).ok());
  EXPECT_FALSE(subscribed.udp_endpoint_known());
  const int same_host = bystander_socket("127.0.0.1");
  const int other_host = bystander_socket("127.0.0.2");
  ASSERT_GE(same_host, 0);
  ASSERT_GE(other_host, 0);
  constexpr int kSpoofed = 5;
  std::uint64_t sequence = 0;
  for (int i = 0; i < kSpoofed; ++i) {
    for (const int from : {same_host, other_host}) {
      const auto bytes = heartbeat(++sequence, key_);
      ::sendto(from, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&server_udp_),
               sizeof server_udp_);
    }
  }
  const v1::Stats counted = wait_for_counts(kSpoofed, kSpoofed);
  EXPECT_EQ(counted.datagrams_foreign_source(), static_cast<std::uint64_t>(kSpoofed));
  v1::StepRequest step;
  step.set_session_id(session_.session_id());
  step.set_ticks(50);
  v1::StepResponse stepped;
  ASSERT_TRUE(call(&v1::Haptic::Stub::Step, step, stepped).ok());

  // This host's bystander gets challenges only, never more bytes than the spoofer sent it; the
  // other host's gets nothing at all.
  std::array<std::uint8_t, 512> buffer{};
  std::size_t challenge_bytes = 0;
  for (ssize_t n; (n = ::recv(same_host, buffer.data(), buffer.size(), 0)) > 0;) {
    wire::Header h;
    ASSERT_EQ(wire::peek_header(std::span(buffer.data(), static_cast<std::size_t>(n)), h),
              wire::DecodeError::kNone);
    EXPECT_EQ(h.type, wire::DatagramType::kPathChallenge);
    challenge_bytes += static_cast<std::size_t>(n);
  }
  EXPECT_GT(challenge_bytes, 0u);
  EXPECT_LE(challenge_bytes, kSpoofed * wire::kHeartbeatDatagramSize);
  EXPECT_LT(::recv(other_host, buffer.data(), buffer.size(), 0), 0);
  EXPECT_EQ(stats().datagrams_sent(), 0u);  // no state went anywhere

  // The client's own address answers its challenge and gets the stream; the bystander still none.
  send(heartbeat(++sequence, key_));
  answer_challenge(++sequence);
  // The response reaches the server's receiver on its own time: ask until it has (bounded).
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  do {
    ASSERT_TRUE(call(&v1::Haptic::Stub::SubscribeState, subscribe, subscribed).ok());
  } while (!subscribed.udp_endpoint_known() && std::chrono::steady_clock::now() < give_up);
  EXPECT_TRUE(subscribed.udp_endpoint_known());
  step.set_ticks(3);
  ASSERT_TRUE(call(&v1::Haptic::Stub::Step, step, stepped).ok());
  for (int i = 0; i < 3; ++i) {
    const ssize_t n = ::recv(socket_, buffer.data(), buffer.size(), 0);
    ASSERT_EQ(n, static_cast<ssize_t>(wire::kStateDatagramSize));
  }
  EXPECT_LT(::recv(same_host, buffer.data(), buffer.size(), 0), 0);
  ::close(same_host);
  ::close(other_host);
}

TEST_F(WireLevel, HeartbeatsPastTheSessionsBudgetAreDroppedAndCounted) {
  constexpr int kSent = 100;  // well within the server socket's default receive buffer: none lost
  const auto start = std::chrono::steady_clock::now();
  for (int i = 1; i <= kSent; ++i) send(heartbeat(static_cast<std::uint64_t>(i), key_));
  // Everything is accounted for, and no more passed than the bucket allows in the time the
  // server can have taken (a burst of 20, then 100 per second), however fast this machine is.
  const auto counted = [&](const v1::Stats& t) {
    return t.datagrams_received() + t.heartbeats_rate_limited();
  };
  v1::Stats all = stats();
  for (int i = 0; i < 500 && counted(all) < kSent; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    all = stats();
  }
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(counted(all), static_cast<std::uint64_t>(kSent));
  EXPECT_GE(all.datagrams_received(), 20u);
  EXPECT_LE(static_cast<double>(all.datagrams_received()), 20.0 + 100.0 * elapsed_s + 1.0);
  EXPECT_EQ(all.datagrams_dropped(), all.heartbeats_rate_limited());
}

TEST_F(WireLevel, SigtermEndsTheServerCleanly) { EXPECT_EQ(server_->stop(), 0); }

}  // namespace
}  // namespace haptic
