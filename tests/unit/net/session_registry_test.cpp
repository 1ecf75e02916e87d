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

UdpAddress host(const char* ip, std::uint16_t port) {
  UdpAddress address = loopback(port);
  ::inet_pton(AF_INET, ip, &reinterpret_cast<sockaddr_in*>(&address.storage)->sin_addr);
  return address;
}

std::uint16_t port_of(const UdpAddress& address) {
  return ntohs(reinterpret_cast<const sockaddr_in*>(&address.storage)->sin_port);
}

using Verdict = HeartbeatOutcome::Verdict;

TEST(SessionRegistry, StateGoesOnlyToAnAddressThatAnsweredItsChallenge) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto session = registry.open("c", 0, "127.0.0.1");
  ASSERT_TRUE(session);
  const auto t0 = SteadyClock::now();
  EXPECT_EQ(registry.subscribe(session->id, 2), std::optional<bool>(false));
  EXPECT_TRUE(registry.subscribers().empty());  // no address yet
  const HeartbeatOutcome first = registry.on_heartbeat(session->id, 1, loopback(4000), t0);
  ASSERT_EQ(first.verdict, Verdict::kChallenge);
  EXPECT_TRUE(registry.subscribers().empty());  // heard from, not yet proven
  EXPECT_EQ(registry.subscribe(session->id, 2), std::optional<bool>(false));
  // A wrong nonce, or the right one from elsewhere, proves nothing.
  EXPECT_FALSE(registry.on_path_response(session->id, 2, first.nonce ^ 1, loopback(4000)));
  EXPECT_FALSE(registry.on_path_response(session->id, 2, first.nonce, loopback(4001)));
  const auto version = registry.subscribers_version();
  EXPECT_TRUE(registry.on_path_response(session->id, 2, first.nonce, loopback(4000)));
  EXPECT_NE(registry.subscribers_version(), version);
  EXPECT_EQ(registry.subscribe(session->id, 2), std::optional<bool>(true));
  ASSERT_EQ(registry.subscribers().size(), 1u);
  EXPECT_EQ(registry.subscribers()[0].decimation, 2u);
  EXPECT_EQ(port_of(registry.subscribers()[0].address), 4000);
  EXPECT_FALSE(registry.on_path_response(session->id, 2, first.nonce, loopback(4000)));  // replayed
  // Heartbeats and responses share one sequence: 2 is spent.
  EXPECT_EQ(registry.on_heartbeat(session->id, 2, loopback(4000), t0).verdict, Verdict::kStale);
  EXPECT_EQ(registry.on_heartbeat(session->id, 3, loopback(4000), t0).verdict, Verdict::kAccepted);

  // The client moves: state stays where it was proven to arrive until the new address answers;
  // one challenge per address per interval.
  const HeartbeatOutcome moved = registry.on_heartbeat(session->id, 5, loopback(4001), t0);
  ASSERT_EQ(moved.verdict, Verdict::kChallenge);
  EXPECT_EQ(registry.on_heartbeat(session->id, 6, loopback(4001), t0 + kChallengeInterval / 2).verdict,
            Verdict::kAccepted);
  EXPECT_EQ(port_of(registry.subscribers()[0].address), 4000);
  const HeartbeatOutcome again = registry.on_heartbeat(session->id, 7, loopback(4001), t0 + kChallengeInterval);
  ASSERT_EQ(again.verdict, Verdict::kChallenge);
  EXPECT_FALSE(registry.on_path_response(session->id, 8, moved.nonce, loopback(4001)));  // superseded
  EXPECT_TRUE(registry.on_path_response(session->id, 9, again.nonce, loopback(4001)));
  EXPECT_EQ(port_of(registry.subscribers()[0].address), 4001);

  // Another host than the one that opened the session: dropped, nothing to send there.
  EXPECT_EQ(registry.on_heartbeat(session->id, 10, host("127.0.0.2", 4000), t0).verdict,
            Verdict::kForeignSource);
  EXPECT_FALSE(registry.on_path_response(session->id, 11, again.nonce, host("10.1.1.1", 4001)));
  EXPECT_EQ(registry.on_heartbeat(12345, 9, loopback(4000), t0).verdict, Verdict::kStale);  // unknown
}

TEST(SessionRegistry, ALatePathResponseDoesNotReopenSpentHeartbeatSequences) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto session = registry.open("c", 0, "127.0.0.1");
  ASSERT_TRUE(session);
  const auto t0 = SteadyClock::now();
  // Heartbeat 1 is challenged; the client answers with response 2, which is held up in the
  // network while heartbeat 3 arrives (within the challenge interval: no new nonce).
  const HeartbeatOutcome first = registry.on_heartbeat(session->id, 1, loopback(4000), t0);
  ASSERT_EQ(first.verdict, Verdict::kChallenge);
  ASSERT_EQ(registry.on_heartbeat(session->id, 3, loopback(4000), t0).verdict, Verdict::kAccepted);
  // Response 2 arrives late, right nonce, right address: its sequence is spent.
  EXPECT_FALSE(registry.on_path_response(session->id, 2, first.nonce, loopback(4000)));
  // Had it moved the counter back to 2, a replay of heartbeat 3 would renew the lease again.
  EXPECT_EQ(registry.on_heartbeat(session->id, 3, loopback(4000), t0).verdict, Verdict::kStale);
  EXPECT_EQ(registry.on_heartbeat(session->id, 2, loopback(4000), t0).verdict, Verdict::kStale);
  EXPECT_EQ(registry.client_statistics(t0)[0].heartbeats, 2u);  // 1 and 3, once each
  // The same answer with a fresh sequence still proves the address.
  EXPECT_TRUE(registry.on_path_response(session->id, 4, first.nonce, loopback(4000)));
  EXPECT_EQ(registry.on_heartbeat(session->id, 4, loopback(4000), t0).verdict, Verdict::kStale);
  EXPECT_EQ(registry.on_heartbeat(session->id, 5, loopback(4000), t0).verdict, Verdict::kAccepted);
}

TEST(SessionRegistry, AnySourceLetsAnotherHostAnswerTheChallenge) {
  SessionRegistry registry(SessionLimits{4, 4, 0, std::chrono::milliseconds(1000), true});
  const auto session = registry.open("behind-nat", 0, "127.0.0.1");
  const HeartbeatOutcome outcome = registry.on_heartbeat(session->id, 1, host("10.9.8.7", 5000));
  ASSERT_EQ(outcome.verdict, Verdict::kChallenge);
  EXPECT_TRUE(registry.on_path_response(session->id, 2, outcome.nonce, host("10.9.8.7", 5000)));
}

TEST(SessionRegistry, HeartbeatsPastTheBudgetAreDroppedUnprocessed) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto session = registry.open("chatty", 0, "127.0.0.1");
  const auto t0 = SteadyClock::now();
  std::uint64_t sequence = 0;
  int accepted = 0;
  for (int i = 0; i < 100; ++i) {  // all at once: only the burst passes
    const Verdict v = registry.on_heartbeat(session->id, ++sequence, loopback(4000), t0).verdict;
    if (v == Verdict::kAccepted || v == Verdict::kChallenge) ++accepted;
  }
  EXPECT_EQ(accepted, static_cast<int>(kHeartbeatBurst));
  // The bucket refills at kHeartbeatRateHz: one more every 10 ms.
  const auto later = t0 + std::chrono::milliseconds(10);
  EXPECT_EQ(registry.on_heartbeat(session->id, ++sequence, loopback(4000), later).verdict,
            Verdict::kAccepted);
  EXPECT_EQ(registry.on_heartbeat(session->id, ++sequence, loopback(4000), later).verdict,
            Verdict::kRateLimited);
  // A limited heartbeat renews nothing, but neither does it spend its sequence number (accepted
  // later; as its address never answered, it is challenged anew).
  EXPECT_EQ(registry.on_heartbeat(session->id, sequence, loopback(4000), later + std::chrono::seconds(1))
                .verdict,
            Verdict::kChallenge);
}

TEST(SessionRegistry, AcknowledgementsOfNewStatesPassTheHeartbeatBudgetAndNoMore) {
  SessionRegistry registry(4, std::chrono::milliseconds(1000));
  const auto session = registry.open("lockstep", 0, "127.0.0.1");
  const auto t0 = SteadyClock::now();
  std::uint64_t sequence = 0;
  const HeartbeatOutcome first = registry.on_heartbeat(session->id, ++sequence, loopback(4000), t0);
  ASSERT_EQ(first.verdict, Verdict::kChallenge);
  ASSERT_TRUE(registry.on_path_response(session->id, ++sequence, first.nonce, loopback(4000)));
  ASSERT_TRUE(registry.subscribe(session->id, 1, 1, 64).has_value());
  const std::vector<Subscriber> subscribers = registry.subscribers();
  ASSERT_EQ(subscribers.size(), 1u);
  EXPECT_EQ(subscribers[0].ack_window, 64u);
  subscribers[0].sequenced->store(1000);  // the sender has numbered 1000 States
  // The budget spent on heartbeats that acknowledge nothing.
  for (int i = 0; i < 100; ++i) registry.on_heartbeat(session->id, ++sequence, loopback(4000), t0);
  EXPECT_EQ(registry.on_heartbeat(session->id, ++sequence, loopback(4000), t0).verdict, Verdict::kRateLimited);
  const auto acknowledge = [&](std::uint64_t last_state_sequence) {
    HeartbeatReport report;
    report.last_state_sequence = last_state_sequence;
    return registry.on_heartbeat(session->id, ++sequence, loopback(4000), t0, report).verdict;
  };
  // An acknowledgement of States not acknowledged before passes, and is kept.
  EXPECT_EQ(acknowledge(256), Verdict::kAccepted);
  EXPECT_EQ(subscribers[0].acknowledged->load(), 256u);
  // The same again acknowledges nothing: charged, and so refused.
  EXPECT_EQ(acknowledge(256), Verdict::kRateLimited);
  // Beyond what was numbered, only what was numbered is believed...
  EXPECT_EQ(acknowledge(5000), Verdict::kAccepted);
  EXPECT_EQ(subscribers[0].acknowledged->load(), 1000u);
  // ...so a key holder gets at most one uncharged heartbeat per State numbered.
  EXPECT_EQ(acknowledge(5001), Verdict::kRateLimited);
  const auto statistics = registry.client_statistics(t0);
  ASSERT_EQ(statistics.size(), 1u);
  EXPECT_EQ(statistics[0].ack_window, 64u);
  EXPECT_EQ(statistics[0].acknowledged_sequence, 1000u);

  // A stream started afresh numbers from 1 again; without a window nothing is exempt.
  ASSERT_TRUE(registry.subscribe(session->id, 0).has_value());
  ASSERT_TRUE(registry.subscribe(session->id, 1, 1, 0).has_value());
  EXPECT_EQ(subscribers[0].sequenced->load(), 0u);
  EXPECT_EQ(subscribers[0].acknowledged->load(), 0u);
  subscribers[0].sequenced->store(10);
  EXPECT_EQ(acknowledge(10), Verdict::kRateLimited);
}

TEST(SessionRegistry, OneHostCannotTakeEverySlot) {
  SessionRegistry registry(SessionLimits{4, 2, 0, std::chrono::milliseconds(1000)});
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

// One token used from several hosts was held to each host's share alone, so two hosts together
// took every slot; its sessions now share the token's share too.
TEST(SessionRegistry, OneTokenFromManyHostsCannotTakeEverySlot) {
  SessionRegistry registry(SessionLimits{8, 4, 2, std::chrono::milliseconds(1000)});
  const Caller observer{"lab-observers", v1::OBSERVER};
  std::string refusal;
  ASSERT_TRUE(registry.open("a", 0, "10.0.0.7", &refusal, observer));
  ASSERT_TRUE(registry.open("b", 0, "10.0.0.8", &refusal, observer));
  EXPECT_FALSE(registry.open("c", 0, "10.0.0.9", &refusal, observer));
  EXPECT_EQ(refusal, "too many sessions open with token 'lab-observers': 2, the most one token may hold "
                     "from all hosts together (2, max_sessions_per_token)");
  // Another token, and no token at all, are not counted against it.
  EXPECT_TRUE(registry.open("d", 0, "10.0.0.9", &refusal, Caller{"rig-1", v1::CONTROLLER}));
  EXPECT_TRUE(registry.open("e", 0, "10.0.0.9", &refusal));
  EXPECT_EQ(registry.token_of(registry.open("f", 0, "10.0.0.10", &refusal, Caller{"rig-2", v1::CONTROLLER})->id),
            "rig-2");
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

TEST(SessionRegistry, SilentSessionsExpireAndRenewedOnesStay) {
  SessionRegistry registry(4, std::chrono::milliseconds(100));
  const auto quiet = registry.open("quiet", 0, "127.0.0.1");
  const auto chatty = registry.open("chatty", 0, "127.0.0.1");
  ASSERT_TRUE(quiet && chatty);
  // Only the lease clock matters; no sleeping: heartbeats and expire() take the time to judge by.
  const auto t0 = SteadyClock::now();
  ASSERT_NE(registry.on_heartbeat(chatty->id, 1, loopback(4000), t0 + std::chrono::milliseconds(80)).verdict,
            HeartbeatOutcome::Verdict::kStale);  // renewed at t0 + 80 ms
  const auto expired = registry.expire(t0 + std::chrono::milliseconds(150));
  EXPECT_EQ(expired, std::vector<std::uint64_t>{quiet->id});  // silent for 150 ms > 100 ms
  EXPECT_EQ(registry.size(), 1u);
  EXPECT_FALSE(registry.device_index_of(quiet->id).has_value());
  EXPECT_TRUE(registry.device_index_of(chatty->id).has_value());  // 70 ms silent: still held
  // Without another word it goes too, once its own lease runs out.
  EXPECT_EQ(registry.expire(t0 + std::chrono::milliseconds(181)), std::vector<std::uint64_t>{chatty->id});
  EXPECT_EQ(registry.size(), 0u);
}

}  // namespace
}  // namespace haptic::net
