// What one client can take from the server, tried from outside with bounded loops on loopback:
// event streams are capped per session and in all (each holds a control-plane thread), refused
// with RESOURCE_EXHAUSTED naming the cap, and end with their session; memory does not grow with
// the attempts, locked memory included (the loop runs with SCHED_FIFO and mlockall where allowed).
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "haptic/io/session_secret.hpp"
#include "haptic/v1/service.grpc.pb.h"
#include "integration/raw_client.hpp"
#include "integration/server_process.hpp"

namespace haptic {
namespace {

using Clock = std::chrono::system_clock;

/// A field of /proc/<pid>/status in kB ("VmRSS", "VmLck"); -1 if absent.
long status_kb(pid_t pid, const std::string& field) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

class ResourceLimits : public ::testing::Test {
 protected:
  // Real time, so that the loop asks for SCHED_FIFO and locks memory as a deployed server does.
  test::ServerProcess server_{R"({"time_mode": "REAL_TIME", "udp_address": "127.0.0.1",
    "status_period_s": 0, "real_time": {"use_fifo": true, "cpu": -1},
    "max_event_streams": 8, "max_event_streams_per_session": 4, "max_event_streams_per_peer": 8,
    "lease_timeout_ms": 10000})"};  // these raw clients send no heartbeats; a flood takes a while
  test::RawClient client_{server_.address()};

  v1::OpenSessionResponse open(const std::string& name) {
    v1::OpenSessionResponse response;
    EXPECT_TRUE(client_.open(response, name).ok());
    return response;
  }

  v1::Stats stats(const v1::OpenSessionResponse& session) { return client_.stats(session); }

  /// One WatchEvents call in flight.
  struct Stream {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<v1::Event>> reader;
  };

  std::unique_ptr<Stream> watch(const v1::OpenSessionResponse& session) {
    auto stream = std::make_unique<Stream>();
    stream->context.set_deadline(Clock::now() + std::chrono::seconds(60));
    stream->context.AddMetadata(io::kSessionSecretMetadataKey, session.session_secret());
    v1::WatchEventsRequest request;
    request.set_session_id(session.session_id());
    stream->reader = client_.stub().WatchEvents(&stream->context, request);
    return stream;
  }

  /// Starts `count` streams at once, then reads each one's first message: the ones the server
  /// took say WATCH_STARTED (kept open in `open`); the others end RESOURCE_EXHAUSTED.
  struct Outcome {
    std::vector<std::unique_ptr<Stream>> open;
    int refused = 0;
    int refused_otherwise = 0;  // any other ending: none expected
    std::string message;        // of one refusal by the cap (not by gRPC's thread quota)
    std::string other_message;  // of one refusal by anything else
  };
  Outcome attempt(const v1::OpenSessionResponse& session, int count) {
    std::vector<std::unique_ptr<Stream>> streams;
    for (int i = 0; i < count; ++i) streams.push_back(watch(session));
    Outcome outcome;
    for (auto& stream : streams) {
      v1::Event first;
      if (stream->reader->Read(&first) && first.kind() == v1::Event::WATCH_STARTED) {
        outcome.open.push_back(std::move(stream));
        continue;
      }
      const grpc::Status status = stream->reader->Finish();
      if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
        ++outcome.refused;
        if (status.error_message().find("event streams") != std::string::npos) outcome.message = status.error_message();
        else outcome.other_message = status.error_message();
      } else {
        ++outcome.refused_otherwise;
        outcome.other_message = std::to_string(static_cast<int>(status.error_code())) + " " +
                                status.error_message();
      }
    }
    return outcome;
  }
};

TEST_F(ResourceLimits, TwoThousandStreamAttemptsAreRefusedPastTheCapsAndMemoryStaysPut) {
  const v1::OpenSessionResponse first = open("flooder");
  const v1::OpenSessionResponse second = open("second");
  const v1::OpenSessionResponse third = open("third");
  // Warm up one stream's worth of machinery before the baseline, on a session of its own that is
  // then closed: its stream ends, and the server has let go of it before the stream's status
  // reaches us (a cancelled stream is let go within the server's next poll, which under load can
  // come after the flood below has been counted against the server-wide cap).
  {
    const v1::OpenSessionResponse warm_up = open("warm-up");
    auto warm = attempt(warm_up, 1);
    ASSERT_EQ(warm.open.size(), 1u);
    v1::SessionRef ref;
    ref.set_session_id(warm_up.session_id());
    v1::Empty empty;
    ASSERT_TRUE(client_.call(&v1::Haptic::Stub::CloseSession, ref, empty, warm_up.session_secret()).ok());
    v1::Event event;
    while (warm.open.front()->reader->Read(&event)) {
    }
    ASSERT_TRUE(warm.open.front()->reader->Finish().ok());
  }
  const long rss_before = status_kb(server_.pid(), "VmRSS");
  const long locked_before = status_kb(server_.pid(), "VmLck");
  const v1::Stats stats_before = stats(first);

  Outcome flood = attempt(first, 2000);
  EXPECT_EQ(flood.open.size(), 4u);  // max_event_streams_per_session
  EXPECT_EQ(flood.refused, 1996);
  EXPECT_EQ(flood.refused_otherwise, 0);
  EXPECT_NE(flood.message.find("already holds 4 event streams, the most one session may (max_event_streams_per_session = 4)"),
            std::string::npos)
      << flood.message;

  // The server-wide cap: 4 + 4 = 8 taken; the third session's are refused naming that cap.
  Outcome more = attempt(second, 4);
  EXPECT_EQ(more.open.size(), 4u) << more.message << " / " << more.other_message;
  Outcome over = attempt(third, 2);
  EXPECT_EQ(over.open.size(), 0u);
  EXPECT_EQ(over.refused, 2);
  EXPECT_NE(over.message.find("its most (max_event_streams = 8)"), std::string::npos) << over.message;

  const long rss_after = status_kb(server_.pid(), "VmRSS");
  const long locked_after = status_kb(server_.pid(), "VmLck");
  const v1::Stats stats_after = stats(first);
  std::printf("  2,006 stream attempts: RSS %ld -> %ld kB, locked mappings %ld -> %ld kB, "
              "loop overruns %llu -> %llu, ticks %llu -> %llu\n",
              rss_before, rss_after, locked_before, locked_after,
              static_cast<unsigned long long>(stats_before.overruns()),
              static_cast<unsigned long long>(stats_after.overruns()),
              static_cast<unsigned long long>(stats_before.ticks()),
              static_cast<unsigned long long>(stats_after.ticks()));
  // Before the caps each stream held a thread whose 8 MB stack mlockall made resident: 16 GB for
  // 2,000. Now the attempts cost what a few calls cost. (VmLck counts the locked mappings' whole
  // size; with MCL_ONFAULT only their resident pages are locked, and those are in VmRSS.)
#if !defined(__SANITIZE_ADDRESS__)  // AddressSanitizer's quarantine keeps freed memory resident
  EXPECT_LT(rss_after - rss_before, 64 * 1024);
#endif
  EXPECT_GT(stats_after.ticks(), stats_before.ticks());  // the loop kept running

  // A stream ends with its session: closing the flooder's session ends its four, cleanly.
  {
    v1::SessionRef ref;
    ref.set_session_id(first.session_id());
    v1::Empty empty;
    ASSERT_TRUE(client_.call(&v1::Haptic::Stub::CloseSession, ref, empty, first.session_secret()).ok());
  }
  for (auto& stream : flood.open) {
    v1::Event event;
    bool closed_seen = false;
    while (stream->reader->Read(&event)) {
      closed_seen = closed_seen || (event.kind() == v1::Event::SESSION_CLOSED &&
                                    event.session_id() == first.session_id());
    }
    EXPECT_TRUE(closed_seen);  // its own ending was delivered before the stream ended
    EXPECT_TRUE(stream->reader->Finish().ok());
  }
  // Their places are free again.
  Outcome again = attempt(third, 4);
  EXPECT_EQ(again.open.size(), 4u);
  for (auto* outcome : {&more, &again}) {
    for (auto& stream : outcome->open) stream->context.TryCancel();
  }
}

// A host that opens and closes sessions in a loop is held to a rate: past the burst, OpenSession
// is refused naming the limits (and nothing is opened), while the bucket refills at its rate.
TEST(ResourceLimitsOfSessions, OneHostsSessionOpeningsAreRateLimitedAfterABurst) {
  test::ServerProcess server(test::lockstep_config(
      R"("session_open_rate_per_peer": 0.5, "session_open_burst_per_peer": 3)"));
  test::RawClient client(server.address());
  const auto open_and_close = [&] {
    v1::OpenSessionResponse session;
    const grpc::Status status = client.open(session, "churn");
    if (status.ok()) {
      v1::SessionRef ref;
      ref.set_session_id(session.session_id());
      v1::Empty empty;
      EXPECT_TRUE(client.call(&v1::Haptic::Stub::CloseSession, ref, empty, session.session_secret()).ok());
    }
    return status;
  };
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(open_and_close().ok()) << i;  // the burst
  const grpc::Status refused = open_and_close();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.error_message().find("too many sessions opened from 127.0.0.1"), std::string::npos)
      << refused.error_message();
  EXPECT_NE(refused.error_message().find("session_open_burst_per_peer"), std::string::npos);
  // One every 2 s (slow, so a loaded machine's slow calls above cannot refill a token early):
  // after 2.1 s one more.
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  EXPECT_TRUE(open_and_close().ok());
}

/// A 10 mm square plate at height `z`: a mesh of two triangles, created for `session`.
grpc::Status add_plate_mesh(test::RawClient& client, const v1::OpenSessionResponse& session, double z) {
  v1::CreateObjectRequest request;
  request.set_session_id(session.session_id());
  request.mutable_object()->mutable_impedance()->set_stiffness(1000.0);
  auto* mesh = request.mutable_object()->mutable_mesh();
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {0.01, 0.0}, {0.01, 0.01}, {0.0, 0.01}}) {
    auto* vertex = mesh->add_vertices();
    vertex->set_x(x);
    vertex->set_y(y);
    vertex->set_z(z);
  }
  for (const std::uint32_t index : {0u, 1u, 2u, 0u, 2u, 3u}) mesh->add_indices(index);
  v1::ItemRef item;
  return client.call(&v1::Haptic::Stub::CreateObject, request, item, session.session_secret());
}

TEST(ResourceLimitsOfTheScene, OneHostsSessionsAndTheWholeScenesTrianglesAreBounded) {
  test::ServerProcess server(test::lockstep_config(
      R"("max_sessions_per_peer": 2, "max_scene_triangles": 3)"));
  test::RawClient client(server.address());
  const auto open = [&](v1::OpenSessionResponse& response) { return client.open(response, "one-host"); };
  v1::OpenSessionResponse first, second, third;
  ASSERT_TRUE(open(first).ok());
  ASSERT_TRUE(open(second).ok());
  const grpc::Status refused = open(third);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(refused.error_message(), "too many sessions open from 127.0.0.1: 2, the most one host "
                                     "may hold (2, max_sessions_per_peer)");

  // Two triangles from one session, two more from another: over the whole scene's three.
  const auto add_plate = [&](const v1::OpenSessionResponse& session, double z) {
    return add_plate_mesh(client, session, z);
  };
  ASSERT_TRUE(add_plate(first, 0.0).ok());
  const grpc::Status over = add_plate(second, 0.01);
  EXPECT_EQ(over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(over.error_message().find("over max_scene_triangles (3)"), std::string::npos)
      << over.error_message();
}

// One session cannot take the whole scene's triangle budget, nor one host every event stream: by
// default each holds at most half (the refusals name the share).
TEST(ResourceLimitsOfTheScene, OneSessionHoldsAtMostItsShareOfTheTriangles) {
  test::ServerProcess server(test::lockstep_config(R"("max_scene_triangles": 8)"));
  test::RawClient client(server.address());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(client.open(session, "greedy").ok());
  const auto add_plate = [&](double z) { return add_plate_mesh(client, session, z); };
  ASSERT_TRUE(add_plate(0.0).ok());
  ASSERT_TRUE(add_plate(0.01).ok());  // 4 triangles: half of the 8
  const grpc::Status over = add_plate(0.02);
  EXPECT_EQ(over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(over.error_message(),
            "object: 2 more triangles would bring the items of the sessions from 127.0.0.1 (fading "
            "items included) to 6, over max_scene_triangles_per_peer (4)");
}

/// A WatchEvents stream held open, and how to ask for one: nullptr, with `refusal` set, when the
/// server refuses it (RESOURCE_EXHAUSTED expected).
struct EventStream {
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReader<v1::Event>> reader;
};
std::unique_ptr<EventStream> watch_events(test::RawClient& client, const v1::OpenSessionResponse& session,
                                          std::string& refusal, const std::string& token = {}) {
  auto stream = std::make_unique<EventStream>();
  stream->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  stream->context.AddMetadata(io::kSessionSecretMetadataKey, session.session_secret());
  if (!token.empty()) stream->context.AddMetadata("authorization", "Bearer " + token);
  v1::WatchEventsRequest request;
  request.set_session_id(session.session_id());
  stream->reader = client.stub().WatchEvents(&stream->context, request);
  v1::Event first;
  if (stream->reader->Read(&first) && first.kind() == v1::Event::WATCH_STARTED) return stream;
  const grpc::Status status = stream->reader->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  refusal = status.error_message();
  return nullptr;
}

TEST(ResourceLimitsOfSessions, OneHostHoldsAtMostItsShareOfTheEventStreams) {
  // The defaults: 32 streams in all, 4 a session, half of the 32 a host. Six sessions of one host
  // ask for 4 streams each.
  test::ServerProcess server(test::lockstep_config(R"("lease_timeout_ms": 10000)"));
  test::RawClient client(server.address());
  std::vector<std::unique_ptr<EventStream>> open;
  int refused = 0;
  std::string message;
  for (int s = 0; s < 6; ++s) {
    v1::OpenSessionResponse session;
    ASSERT_TRUE(client.open(session, "watcher-" + std::to_string(s)).ok());
    for (int i = 0; i < 4; ++i) {
      if (auto stream = watch_events(client, session, message)) {
        open.push_back(std::move(stream));
      } else {
        ++refused;
      }
    }
  }
  EXPECT_EQ(open.size(), 16u);
  EXPECT_EQ(refused, 8);
  EXPECT_EQ(message, "the sessions from 127.0.0.1 already hold 16 event streams, the most one host "
                     "may (max_event_streams_per_peer = 16)");
  for (auto& stream : open) stream->context.TryCancel();
}

// A token's sessions share a token's share as well as their host's: one OBSERVER token cannot hold
// every stream by being used from several hosts (unit tests: two hosts; here its share, 3, is
// below the host's, 16, so one host shows it).
TEST(ResourceLimitsOfSessions, OneTokenHoldsAtMostItsShareOfTheEventStreamsAndSessions) {
  constexpr const char* kObserver = "observer-token-0123456789abc";
  test::ServerProcess server(test::lockstep_config(
      R"("lease_timeout_ms": 10000, "max_event_streams_per_token": 3, "max_sessions_per_token": 4,
         "security": {"tokens": [{"name": "lab-observers", "token": ")" + std::string(kObserver) +
      R"(", "role": "OBSERVER"}]})"));
  test::RawClient client(server.address(), std::nullopt, kObserver);
  std::vector<std::unique_ptr<EventStream>> open;
  std::string message;
  for (int s = 0; s < 4; ++s) {  // four sessions, a stream each
    v1::OpenSessionResponse session;
    ASSERT_TRUE(client.open(session, "observer-" + std::to_string(s)).ok());
    if (auto stream = watch_events(client, session, message, kObserver)) open.push_back(std::move(stream));
  }
  EXPECT_EQ(open.size(), 3u);
  EXPECT_EQ(message, "the sessions of token 'lab-observers' already hold 3 event streams, the most one "
                     "token may from all hosts together (max_event_streams_per_token = 3)");
  v1::OpenSessionResponse fifth;
  const grpc::Status refused = client.open(fifth, "observer-5");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.error_message().find("too many sessions open with token 'lab-observers': 4"),
            std::string::npos) << refused.error_message();
  for (auto& stream : open) stream->context.TryCancel();
}

/// `count` TCP connections to `port` on loopback that never say a word.
std::vector<int> flood(std::uint16_t port, int count) {
  std::vector<int> sockets;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  for (int i = 0; i < count; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) break;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
      ::close(fd);
      continue;
    }
    sockets.push_back(fd);
  }
  return sockets;
}

/// Waits (bounded) until the server has dealt with `count` flood connections: each either held
/// open or refused.
v1::Stats wait_until_accounted(test::RawClient& client, const v1::OpenSessionResponse& session,
                               std::uint64_t count) {
  v1::Stats s = client.stats(session);
  for (int i = 0; i < 1000 && s.connections_refused() + s.connections_open() < count; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    s = client.stats(session);
  }
  return s;
}

/// A new connection opens a session within `within` (retrying, as a client would).
bool opens_again(const std::string& address, std::chrono::seconds within) {
  const auto give_up = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < give_up) {
    test::RawClient fresh(address);
    v1::OpenSessionResponse session;
    if (fresh.open(session, "fresh", std::chrono::seconds(2)).ok()) return true;
  }
  return false;
}

TEST(ConnectionFlood, TheControlPlaneAcceptsAgainAfterRunningOutOfDescriptors) {
  // 128 descriptors and caps far above that: 400 idle connections exhaust the fds themselves.
  // (gRPC's own listener stopped for good at the first failed accept: deaf until a restart.)
  test::ServerProcess server(
      test::lockstep_config(R"("max_connections": 1000, "max_connections_per_peer": 1000)"), {}, 128);
  test::RawClient existing(server.address());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(existing.open(session, "existing").ok());

  std::vector<int> sockets = flood(server.grpc_port(), 400);
  ASSERT_EQ(sockets.size(), 400u);
  // Every one is dealt with, held or closed at once (none left in the backlog), and the client
  // already connected is served all along.
  const v1::Stats during = wait_until_accounted(existing, session, 401);
  std::printf("  flood of 400 with 128 fds: %u open, %llu refused for want of a descriptor\n",
              during.connections_open(), static_cast<unsigned long long>(during.connections_refused()));
  EXPECT_EQ(during.connections_open() + during.connections_refused(), 401u);
  EXPECT_GE(during.connections_refused(), 400u - 128u);
  for (const int fd : sockets) ::close(fd);

  EXPECT_TRUE(opens_again(server.address(), std::chrono::seconds(5)));
}

TEST(ConnectionFlood, ConnectionsPastThePerHostCapAreClosedAtOnceAndOthersGoOn) {
  test::ServerProcess server(test::lockstep_config(R"("max_connections_per_peer": 16)"));
  test::RawClient existing(server.address());
  v1::OpenSessionResponse session;
  ASSERT_TRUE(existing.open(session, "existing").ok());
  std::vector<int> sockets = flood(server.grpc_port(), 100);
  ASSERT_EQ(sockets.size(), 100u);
  const v1::Stats during = wait_until_accounted(existing, session, 101);
  EXPECT_EQ(during.connections_open(), 16u);  // the cap, the existing client's included
  EXPECT_EQ(during.connections_refused(), 100u + 1u - 16u);
  // A refused connection is closed by the server at once: reading it ends.
  char byte = 0;
  int ended = 0;
  for (const int fd : sockets) {
    timeval timeout{0, 1000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    if (::recv(fd, &byte, 1, 0) == 0) ++ended;
  }
  EXPECT_GE(ended, 100 - 15);
  for (const int fd : sockets) ::close(fd);
  EXPECT_TRUE(opens_again(server.address(), std::chrono::seconds(5)));
}

}  // namespace
}  // namespace haptic
