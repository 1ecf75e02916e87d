// The lock-free hand-offs around the loop: LatestValue, SampleRing, SnapshotExchange, and the
// lateness histogram's percentiles.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
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
  // The writer runs ahead of the reader, but never by more than half the ring: a reader that
  // keeps up that well must get every sample, whole and in order, while they are being written.
  constexpr std::uint64_t kTicks = 50000;
  constexpr std::uint64_t kMaxLead = SampleRing::kCapacity / 2;
  SampleRing ring;
  std::atomic<std::uint64_t> consumed{0};
  std::thread writer([&] {
    for (std::uint64_t t = 1; t <= kTicks; ++t) {
      while (t - consumed.load(std::memory_order_acquire) > kMaxLead) std::this_thread::yield();
      ring.publish(sample_for(t));
    }
  });
  std::uint64_t next = 1, missed = 0;
  while (next <= kTicks) {
    ring.wait_beyond(next - 1);
    const std::uint64_t newest = ring.newest();
    for (; next <= newest; ++next) {
      TickSample s;
      if (!ring.read(next, s)) {
        ++missed;
      } else {
        ASSERT_EQ(s.tick, next);
        ASSERT_EQ(s.time_ns, static_cast<std::int64_t>(next) * 1000);
        ASSERT_EQ(s.p_WT.x, -s.p_WT.z);  // never torn
      }
      consumed.store(next, std::memory_order_release);
    }
  }
  writer.join();
  EXPECT_EQ(missed, 0u);
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
  // Heap-allocated and released only if the waiter wakes: a ring whose stop() failed to wake it
  // makes this test fail within two seconds (the thread is then abandoned) instead of hanging.
  auto ring = std::make_shared<SampleRing>();
  ring->publish(sample_for(1));
  auto woke = std::make_shared<std::atomic<bool>>(false);
  std::thread waiter([ring, woke] {
    ring->wait_beyond(1);
    woke->store(true, std::memory_order_release);
  });
  // It waits: nothing newer than tick 1 has been published.
  const auto waiting_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(20);
  while (std::chrono::steady_clock::now() < waiting_until) {
    ASSERT_FALSE(woke->load(std::memory_order_acquire)) << "wait_beyond returned with nothing new";
    std::this_thread::yield();
  }
  ring->stop();
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (!woke->load(std::memory_order_acquire) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const bool did_wake = woke->load(std::memory_order_acquire);
  if (did_wake) {
    waiter.join();
  } else {
    waiter.detach();
  }
  EXPECT_TRUE(did_wake) << "stop() did not wake a thread in wait_beyond()";
  EXPECT_TRUE(ring->stopping());
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
  const std::int64_t now = 5'000'000'000;
  for (int i = 0; i < 980; ++i) histogram.record(10'000, now);   // 10 µs
  for (int i = 0; i < 20; ++i) histogram.record(2'500'000, now);  // 2.5 ms: the top 2 %
  const LatenessSummary summary = histogram.summarize(now);
  EXPECT_EQ(summary.samples, 1000u);
  EXPECT_DOUBLE_EQ(summary.p50_us, 10.0);
  EXPECT_DOUBLE_EQ(summary.p99_us, 2500.0);
  EXPECT_DOUBLE_EQ(summary.max_us, 2500.0);
  EXPECT_DOUBLE_EQ(summary.window_s, 10.0);
  histogram.record(-5, now);  // early wake counts as zero lateness
  EXPECT_EQ(histogram.summarize(now).samples, 1001u);
}

// A stall leaves the figures once it is older than the window: they show the loop now.
TEST(LatenessHistogram, AStallLeavesTheSummaryOnceOlderThanTheWindow) {
  constexpr std::int64_t kSecond = 1'000'000'000;
  LatenessHistogram histogram(3);  // the last 3 whole seconds and the current one
  histogram.record(50'000'000, 10 * kSecond);  // a 50 ms stall at t = 10 s
  // 1 kHz of 5 µs wakes from then on.
  std::int64_t t = 10 * kSecond;
  const auto run_until = [&](std::int64_t end) {
    for (; t < end; t += 1'000'000) histogram.record(5'000, t);
  };
  run_until(13 * kSecond + kSecond / 2);
  LatenessSummary summary = histogram.summarize(t);
  EXPECT_DOUBLE_EQ(summary.max_us, 50'000.0);  // t = 13.5 s: second 10 is still in the window
  EXPECT_EQ(summary.samples, 3'501u);
  run_until(14 * kSecond + kSecond / 2);
  summary = histogram.summarize(t);
  EXPECT_DOUBLE_EQ(summary.max_us, 5.0);  // t = 14.5 s: seconds 11–14 only
  EXPECT_EQ(summary.samples, 3'500u);
  EXPECT_DOUBLE_EQ(summary.p999_us, 5.0);
  // Read long after the last sample, nothing is left in the window.
  EXPECT_EQ(histogram.summarize(t + 10 * kSecond).samples, 0u);
}

}  // namespace
}  // namespace haptic::runtime
