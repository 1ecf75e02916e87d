// What the state sender sends when it wakes: every due tick in lockstep; in real time, when it has
// fallen behind, only each subscriber's newest due sample (the older ones skipped and counted).
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "net/udp_endpoint.hpp"

namespace haptic::net {
namespace {

Subscriber subscriber(std::uint32_t decimation, std::uint64_t first_tick) {
  Subscriber s;
  s.decimation = decimation;
  s.first_tick = first_tick;
  return s;
}

std::vector<std::pair<std::size_t, std::uint64_t>> pairs(const std::vector<PlannedSend>& plan) {
  std::vector<std::pair<std::size_t, std::uint64_t>> out;
  for (const PlannedSend& send : plan) out.emplace_back(send.subscriber, send.tick);
  return out;
}

using Pairs = std::vector<std::pair<std::size_t, std::uint64_t>>;

const std::vector<Subscriber> kSubscribers = {subscriber(1, 1), subscriber(2, 1), subscriber(5, 8)};

TEST(StateSender, LockstepSendsEveryDueTickInTickOrder) {
  std::vector<PlannedSend> plan;
  std::uint64_t skipped = 0;
  plan_sends(kSubscribers, 0, 6, false, plan, skipped);
  EXPECT_EQ(pairs(plan), (Pairs{{0, 1}, {0, 2}, {1, 2}, {0, 3}, {0, 4}, {1, 4}, {0, 5}, {0, 6}, {1, 6}}));
  EXPECT_EQ(skipped, 0u);
  plan_sends(kSubscribers, 6, 10, false, plan, skipped);  // tick 10: the third's first due one
  EXPECT_EQ(pairs(plan), (Pairs{{0, 7}, {0, 8}, {1, 8}, {0, 9}, {0, 10}, {1, 10}, {2, 10}}));
}

TEST(StateSender, BehindInRealTimeItSendsEachSubscribersNewestAndCountsTheRest) {
  std::vector<PlannedSend> plan;
  std::uint64_t skipped = 0;
  // Ten ticks published since the last wake-up (the host was busy): one datagram each, the newest.
  plan_sends(kSubscribers, 0, 10, true, plan, skipped);
  EXPECT_EQ(pairs(plan), (Pairs{{0, 10}, {1, 10}, {2, 10}}));
  EXPECT_EQ(skipped, 9u + 4u);  // ticks 1-9 for the first, 2-8 even for the second
  // Keeping up (one tick per wake-up) nothing is skipped: the same as lockstep.
  skipped = 0;
  plan_sends(kSubscribers, 10, 11, true, plan, skipped);
  EXPECT_EQ(pairs(plan), (Pairs{{0, 11}}));
  plan_sends(kSubscribers, 11, 12, true, plan, skipped);
  EXPECT_EQ(pairs(plan), (Pairs{{0, 12}, {1, 12}}));
  EXPECT_EQ(skipped, 0u);
  // A subscriber's newest due tick need not be the newest tick: 15 for every 5th.
  plan_sends(kSubscribers, 12, 16, true, plan, skipped);
  EXPECT_EQ(pairs(plan), (Pairs{{2, 15}, {0, 16}, {1, 16}}));
  EXPECT_EQ(skipped, 3u + 1u);  // 13-15 for the first, 14 for the second
}

}  // namespace
}  // namespace haptic::net
