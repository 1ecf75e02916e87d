// Sessions: unguessable ids, heartbeat sequencing, subscriptions and lease expiry.
#include <gtest/gtest.h>

#include <arpa/inet.h>

#include <set>

#include "net/session_registry.hpp"

namespace haptic::net {
namespace {

UdpAddress loopback(std::uint16_t port) {
  UdpAddress address;
  auto* in = reinterpret_cast<sockaddr_in*>(&address.storage);
  in->sin_family = AF_INET;
  in->sin_port = htons(port);
  in->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.length = sizeof(sockaddr_in);
  return address;
}

TEST(SessionRegistry, OpensDistinctSessionsUpToTheLimit) {
  SessionRegistry registry(3, std::chrono::milliseconds(1000));
  std::set<std::uint64_t> ids;
  for (int i = 0; i < 3; ++i) {
    const auto session = registry.open("client");
    ASSERT_TRUE(session);
    EXPECT_NE(session->id, 0u);
    ids.insert(session->id);
  }
  EXPECT_EQ(ids.size(), 3u);
  EXPECT_FALSE(registry.open("one too many"));
  EXPECT_TRUE(registry.close(*ids.begin()));
  EXPECT_TRUE(registry.open("room again"));
}

TEST(SessionRegistry, HeartbeatsSetTheAddressAndStaleOnesAreRejected) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto session = registry.open("c");
  ASSERT_TRUE(session);
  EXPECT_EQ(registry.subscribe(session->id, 2), std::optional<bool>(false));
  EXPECT_TRUE(registry.subscribers().empty());  // no address yet
  const auto version = registry.subscribers_version();
  EXPECT_TRUE(registry.on_heartbeat(session->id, 1, loopback(4000)));
  EXPECT_NE(registry.subscribers_version(), version);
  EXPECT_EQ(registry.subscribe(session->id, 2), std::optional<bool>(true));
  ASSERT_EQ(registry.subscribers().size(), 1u);
  EXPECT_EQ(registry.subscribers()[0].decimation, 2u);
  EXPECT_FALSE(registry.on_heartbeat(session->id, 1, loopback(4000)));  // replayed
  EXPECT_TRUE(registry.on_heartbeat(session->id, 5, loopback(4001)));   // client moved
  EXPECT_EQ(ntohs(reinterpret_cast<const sockaddr_in*>(&registry.subscribers()[0].address.storage)
                      ->sin_port),
            4001);
  EXPECT_FALSE(registry.on_heartbeat(12345, 9, loopback(4000)));  // unknown session
}

TEST(SessionRegistry, OneHostCannotTakeEverySlot) {
  SessionRegistry registry(SessionLimits{4, 2, std::chrono::milliseconds(1000)});
  std::string refusal;
  ASSERT_TRUE(registry.open("a", 0, "10.0.0.7"));
  ASSERT_TRUE(registry.open("b", 0, "10.0.0.7"));
  EXPECT_FALSE(registry.open("c", 0, "10.0.0.7", &refusal));
  EXPECT_EQ(refusal, "too many sessions open from 10.0.0.7: 2, the most one host may hold (2, "
                     "max_sessions_per_peer)");
  ASSERT_TRUE(registry.open("d", 0, "10.0.0.8"));  // another host still gets in
  const auto last = registry.open("e", 0, "10.0.0.9");
  ASSERT_TRUE(last);
  EXPECT_EQ(last->peer, "10.0.0.9");
  EXPECT_FALSE(registry.open("f", 0, "10.0.0.10", &refusal));
  EXPECT_EQ(refusal, "too many sessions open: the server's most is 4 (max_sessions)");
}

TEST(SessionRegistry, PeerHostIsTheAddressOfAGrpcPeer) {
  EXPECT_EQ(peer_host("ipv4:10.0.0.7:5123"), "10.0.0.7");
  EXPECT_EQ(peer_host("ipv6:[::1]:5123"), "::1");
  EXPECT_EQ(peer_host("ipv6:%5B::1%5D:5123"), "::1");
  EXPECT_EQ(peer_host("ipv6:[::ffff:127.0.0.1]:80"), "127.0.0.1");  // dual-stack socket
  EXPECT_EQ(peer_host("ipv6:[fe80::1]:80"), "fe80::1");
  EXPECT_EQ(peer_host("unix:/tmp/socket"), "unix:/tmp/socket");
}

TEST(SessionRegistry, OnlyTheSessionsOwnSecretGrantsAccess) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto alice = registry.open("alice");
  const auto bob = registry.open("bob");
  ASSERT_TRUE(alice && bob);
  EXPECT_NE(alice->secret, bob->secret);
  EXPECT_NE(alice->secret, SessionSecret{});
  const std::span<const std::uint8_t> alices(alice->secret), bobs(bob->secret);
  EXPECT_EQ(registry.authorize(alice->id, alices), Access::kGranted);
  EXPECT_EQ(registry.authorize(alice->id, bobs), Access::kWrongSecret);
  EXPECT_EQ(registry.authorize(alice->id, {}), Access::kWrongSecret);
  EXPECT_EQ(registry.authorize(alice->id, alices.first(15)), Access::kWrongSecret);
  SessionSecret flipped = alice->secret;
  flipped[15] ^= 0x80;  // the last byte counts as much as the first
  EXPECT_EQ(registry.authorize(alice->id, flipped), Access::kWrongSecret);
  EXPECT_EQ(registry.authorize(12345, alices), Access::kNoSuchSession);
  ASSERT_TRUE(registry.close(alice->id));
  EXPECT_EQ(registry.authorize(alice->id, alices), Access::kNoSuchSession);
}

TEST(SessionRegistry, SilentSessionsExpire) {
  SessionRegistry registry(4, std::chrono::milliseconds(100));
  const auto quiet = registry.open("quiet");
  const auto chatty = registry.open("chatty");
  const auto later = SteadyClock::now() + std::chrono::milliseconds(150);
  // Only the lease clock matters; no sleeping: expire() takes the time to judge by.
  auto expired = registry.expire(later);
  EXPECT_EQ(expired.size(), 2u);
  EXPECT_EQ(registry.size(), 0u);
  EXPECT_FALSE(registry.touch(quiet->id));
  EXPECT_FALSE(registry.touch(chatty->id));
}

}  // namespace
}  // namespace haptic::net
