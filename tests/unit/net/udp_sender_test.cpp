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

TEST(StateSender, ConflatedSamplesAreNumberedWithTheOneSent) {
  std::vector<PlannedSend> plan;
  std::uint64_t skipped = 0;
  plan_sends(kSubscribers, 0, 10, true, plan, skipped);
  ASSERT_EQ(plan.size(), 3u);
  EXPECT_EQ(plan[0].skipped_before, 9u);  // ticks 1-9: the sequence jumps by 10 to tick 10's
  EXPECT_EQ(plan[1].skipped_before, 4u);  // 2, 4, 6, 8
  EXPECT_EQ(plan[2].skipped_before, 0u);  // 10 is its first
  plan_sends(kSubscribers, 0, 10, false, plan, skipped);
  for (const PlannedSend& send : plan) EXPECT_EQ(send.skipped_before, 0u);
}

TEST(StateSender, AFlowControlledSubscribersTicksStopWhereItsWindowIsFull) {
  Subscriber every = subscriber(1, 1);
  every.ack_window = 16;
  EXPECT_EQ(flow_limit(every, 0, 0, 0), 16u);    // a window's worth
  EXPECT_EQ(flow_limit(every, 16, 0, 16), 16u);  // full: nothing more
  EXPECT_EQ(flow_limit(every, 16, 4, 16), 20u);  // four acknowledged, four more
  EXPECT_EQ(flow_limit(every, 16, 99, 16), 32u); // an acknowledgement past what was numbered counts as all
  // Every 5th from tick 8: due ticks 10, 15, ... 85 are the window's 16; ticks up to 89 are free.
  Subscriber fifth = subscriber(5, 8);
  fifth.ack_window = 16;
  EXPECT_EQ(flow_limit(fifth, 0, 0, 0), 89u);
  EXPECT_EQ(flow_limit(fifth, 16, 0, 89), 89u);
  Subscriber unpaced = subscriber(1, 1);
  EXPECT_EQ(flow_limit(unpaced, 1'000'000, 0, 0), ~std::uint64_t{0});  // no window: no limit
}

}  // namespace
}  // namespace haptic::net
