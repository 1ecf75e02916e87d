// The lock-free hand-offs around the loop: LatestValue, SampleRing, SnapshotExchange, and the
// lateness histogram's percentiles.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "runtime/latest_value.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/sample_ring.hpp"
#include "runtime/snapshot_exchange.hpp"

namespace haptic::runtime {
namespace {

struct Pair {
  std::uint64_t a = 0;
  std::uint64_t b = 0;  // always a * 3 when written
};

TEST(LatestValue, ReaderNeverSeesATornValue) {
  LatestValue<Pair> mailbox;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= 200000; ++i) mailbox.store(Pair{i, i * 3});
    done = true;
  });
  std::uint64_t last = 0;
  std::uint64_t reads = 0;
  while (!done || reads == 0) {
    const Pair p = mailbox.load();
    ASSERT_EQ(p.b, p.a * 3);
    ASSERT_GE(p.a, last);  // values only move forward
    last = p.a;
    ++reads;
  }
  writer.join();
  EXPECT_EQ(mailbox.load().a, 200000u);
}

TickSample sample_for(std::uint64_t tick) {
  TickSample s;
  s.tick = tick;
  s.time_ns = static_cast<std::int64_t>(tick) * 1000;
  s.p_WT = {static_cast<double>(tick), 0.0, -static_cast<double>(tick)};
  return s;
}

TEST(SampleRing, DeliversEverySampleInOrderToAReaderThatKeepsUp) {
  SampleRing ring;
  std::thread writer([&] {
    for (std::uint64_t t = 1; t <= 50000; ++t) ring.publish(sample_for(t));
  });
  std::uint64_t next = 1, missed = 0;
  while (next <= 50000) {
    ring.wait_beyond(next - 1);
    const std::uint64_t newest = ring.newest();
    for (; next <= newest; ++next) {
      TickSample s;
      if (!ring.read(next, s)) {
        ++missed;  // lapped: allowed, but never a torn or wrong sample
        continue;
      }
      ASSERT_EQ(s.tick, next);
      ASSERT_EQ(s.time_ns, static_cast<std::int64_t>(next) * 1000);
      ASSERT_EQ(s.p_WT.x, -s.p_WT.z);
    }
  }
  writer.join();
  EXPECT_LT(missed, 50000u);
}

TEST(SampleRing, OverwrittenSampleReadsAsMissing) {
  SampleRing ring;
  for (std::uint64_t t = 1; t <= SampleRing::kCapacity + 5; ++t) ring.publish(sample_for(t));
  TickSample s;
  EXPECT_FALSE(ring.read(3, s));
  EXPECT_TRUE(ring.read(SampleRing::kCapacity + 3, s));
  EXPECT_EQ(s.tick, SampleRing::kCapacity + 3);
}

TEST(SampleRing, StopWakesAWaiter) {
  SampleRing ring;
  ring.publish(sample_for(1));
  std::thread waiter([&] { ring.wait_beyond(1); });
  ring.stop();
  waiter.join();
  EXPECT_TRUE(ring.stopping());
}

TEST(SnapshotExchange, LoopSeesNewestAndOldSnapshotsAreFreedOnlyAfterAdoption) {
  SnapshotExchange<int> exchange(std::make_unique<const int>(1));
  EXPECT_EQ(exchange.adopt(), 1);
  exchange.publish(std::make_unique<const int>(2));
  exchange.publish(std::make_unique<const int>(3));
  // The loop adopted generation 1 only: 2 and 3 must be kept, and 1 may be in use.
  EXPECT_EQ(exchange.retained(), 3u);
  EXPECT_EQ(exchange.adopt(), 3);
  exchange.reclaim();
  EXPECT_EQ(exchange.retained(), 1u);
  EXPECT_EQ(exchange.adopted_generation(), 3u);
}

TEST(LatenessHistogram, PercentilesFromKnownSamples) {
  LatenessHistogram histogram;
  for (int i = 0; i < 980; ++i) histogram.record(10'000);   // 10 µs
  for (int i = 0; i < 20; ++i) histogram.record(2'500'000);  // 2.5 ms: the top 2 %
  const LatenessSummary summary = histogram.summarize();
  EXPECT_EQ(summary.samples, 1000u);
  EXPECT_DOUBLE_EQ(summary.p50_us, 10.0);
  EXPECT_DOUBLE_EQ(summary.p99_us, 2500.0);
  EXPECT_DOUBLE_EQ(summary.max_us, 2500.0);
  histogram.record(-5);  // early wake counts as zero lateness
  EXPECT_EQ(histogram.summarize().samples, 1001u);
}

}  // namespace
}  // namespace haptic::runtime
