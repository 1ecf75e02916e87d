// WatchEvents fan-out: every watcher gets every event; watches are capped per session and in all;
// a session's watches end with it, after what was queued for them.
#include <gtest/gtest.h>

#include <chrono>

#include "net/event_hub.hpp"

namespace haptic::net {
namespace {

using std::chrono::milliseconds;

v1::Event event_of(v1::Event::Kind kind, std::uint64_t session_id) {
  v1::Event event;
  event.set_kind(kind);
  event.set_session_id(session_id);
  return event;
}

TEST(EventHub, OneHostsSessionsHoldNoMoreThanTheHostsShareOfTheStreams) {
  EventHub hub(WatchLimits{4, 32, 3});
  std::string refusal;
  // Three sessions from one host, one stream each, then a fourth: over the host's share.
  std::vector<std::shared_ptr<EventHub::Watcher>> held;
  for (std::uint64_t session = 1; session <= 3; ++session) {
    held.push_back(hub.watch(session, refusal, "10.0.0.1"));
    ASSERT_NE(held.back(), nullptr) << refusal;
  }
  EXPECT_EQ(hub.watch(4, refusal, "10.0.0.1"), nullptr);
  EXPECT_EQ(refusal, "the sessions from 10.0.0.1 already hold 3 event streams, the most one host may "
                     "(max_event_streams_per_peer = 3)");
  EXPECT_NE(hub.watch(5, refusal, "10.0.0.2"), nullptr);  // another host has its own
  hub.unwatch(held.front());
  EXPECT_NE(hub.watch(4, refusal, "10.0.0.1"), nullptr);  // room again
}

// One OBSERVER token used from two hosts held all 32 streams (16 a host); a token's sessions now
// share its own share as well, from however many hosts.
TEST(EventHub, OneTokensSessionsFromManyHostsHoldNoMoreThanTheTokensShare) {
  EventHub hub(WatchLimits{4, 32, 16, 3});
  std::string refusal;
  std::vector<std::shared_ptr<EventHub::Watcher>> held;
  for (std::uint64_t session = 1; session <= 3; ++session) {
    held.push_back(hub.watch(session, refusal, "10.0.0." + std::to_string(session), "lab-observers"));
    ASSERT_NE(held.back(), nullptr) << refusal;
  }
  EXPECT_EQ(hub.watch(4, refusal, "10.0.0.4", "lab-observers"), nullptr);
  EXPECT_EQ(refusal, "the sessions of token 'lab-observers' already hold 3 event streams, the most one "
                     "token may from all hosts together (max_event_streams_per_token = 3)");
  EXPECT_NE(hub.watch(5, refusal, "10.0.0.4", "rig-1"), nullptr);  // another token has its own
  EXPECT_NE(hub.watch(6, refusal, "10.0.0.4"), nullptr);           // no token: no such share
  hub.unwatch(held.front());
  EXPECT_NE(hub.watch(4, refusal, "10.0.0.4", "lab-observers"), nullptr);  // room again
}

TEST(EventHub, WatchesAreCappedPerSessionAndInAllNamingTheLimit) {
  EventHub hub(WatchLimits{2, 3});
  std::string refusal;
  auto a1 = hub.watch(1, refusal);
  auto a2 = hub.watch(1, refusal);
  ASSERT_TRUE(a1 && a2);
  EXPECT_EQ(hub.watch(1, refusal), nullptr);
  EXPECT_EQ(refusal, "session 0000000000000001 already holds 2 event streams, the most one session may "
                     "(max_event_streams_per_session = 2)");
  auto b1 = hub.watch(2, refusal);
  ASSERT_TRUE(b1);
  EXPECT_EQ(hub.watch(3, refusal), nullptr);
  EXPECT_EQ(refusal,
            "the server already serves 3 event streams, its most (max_event_streams = 3)");
  hub.unwatch(a1);
  EXPECT_NE(hub.watch(3, refusal), nullptr);  // room again
  EXPECT_EQ(hub.size(), 3u);
}

TEST(EventHub, ASessionsWatchesEndWithItAfterDeliveringWhatWasQueued) {
  EventHub hub;
  std::string refusal;
  auto mine = hub.watch(7, refusal);
  auto other = hub.watch(8, refusal);
  hub.publish(event_of(v1::Event::SCENE_CHANGED, 7));
  hub.publish(event_of(v1::Event::SESSION_CLOSED, 7));
  hub.end_session(7);
  hub.publish(event_of(v1::Event::SCENE_CHANGED, 8));  // after the end: not for the ended watch
  EXPECT_FALSE(mine->finished());                      // two events still to deliver
  ASSERT_EQ(mine->next(milliseconds(0))->kind(), v1::Event::SCENE_CHANGED);
  ASSERT_EQ(mine->next(milliseconds(0))->kind(), v1::Event::SESSION_CLOSED);
  EXPECT_FALSE(mine->next(milliseconds(0)));
  EXPECT_TRUE(mine->finished());
  // The other session's watch goes on and has seen all three.
  EXPECT_FALSE(other->finished());
  int seen = 0;
  while (other->next(milliseconds(0))) ++seen;
  EXPECT_EQ(seen, 3);
  EXPECT_FALSE(other->finished());
  hub.close();
  EXPECT_TRUE(other->finished());
  EXPECT_EQ(hub.watch(9, refusal), nullptr);  // no new watch during shutdown
}

}  // namespace
}  // namespace haptic::net
