#pragma once
// Hand-off of per-tick samples from the loop (one writer) to the data-plane sender (readers).
// A fixed ring of slots, each guarded by its own sequence number (seqlock): the writer never waits;
// a reader that falls more than a ring behind skips ahead and counts what it lost.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "runtime/latest_value.hpp"
#include "runtime/tick_sample.hpp"

namespace haptic::runtime {

class SampleRing {
 public:
  static constexpr std::size_t kCapacity = 1024;  // ≥ 0.1 s at 10 kHz

  /// On the loop: publish the sample of tick `sample.tick` (strictly increasing, from 1).
  void publish(const TickSample& sample) {
    slots_[sample.tick % kCapacity].store(sample);
    published_.store(sample.tick, std::memory_order_release);
    // Wakes a sender blocked in wait_beyond(). A 32-bit counter, because libstdc++ waits on those
    // with a futex on the word itself; wider atomics go through a shared waiter table.
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_all();
  }

  /// Tick index of the newest published sample, 0 before the first.
  std::uint64_t newest() const { return published_.load(std::memory_order_acquire); }

  /// Blocks until a sample newer than `tick` is published, the ticks restart (epoch() moves on
  /// from `epoch`) or stop() is called.
  void wait_beyond(std::uint64_t tick, std::uint32_t epoch) const {
    for (;;) {
      const std::uint32_t seen = signal_.load(std::memory_order_acquire);
      if (published_.load(std::memory_order_acquire) > tick || epoch_.load(std::memory_order_acquire) != epoch ||
          stopping()) {
        return;
      }
      signal_.wait(seen, std::memory_order_acquire);
    }
  }

  /// The same within the present epoch.
  void wait_beyond(std::uint64_t tick) const { wait_beyond(tick, epoch()); }

  /// Off the loop, while it runs no tick (a lockstep reset): the ticks start again from 1. Readers
  /// see epoch() change and start over. Old samples stay in their slots until overwritten; readers
  /// read only published ticks (up to newest()), whose slots the new run has written.
  void restart() {
    published_.store(0, std::memory_order_release);
    epoch_.fetch_add(1, std::memory_order_acq_rel);
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_all();
  }
  /// Bumped by every restart().
  std::uint32_t epoch() const { return epoch_.load(std::memory_order_acquire); }

  /// Wakes waiters for good (shutdown): stopping() turns true and newest() moves past the last
  /// real sample, whose slot then reads as missing.
  void stop() {
    stopping_.store(true, std::memory_order_release);
    published_.fetch_add(1, std::memory_order_acq_rel);
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_all();
  }
  bool stopping() const { return stopping_.load(std::memory_order_acquire); }

  /// Reads the sample of tick `tick` if it is still in the ring; false if it was overwritten.
  bool read(std::uint64_t tick, TickSample& out) const {
    out = slots_[tick % kCapacity].load();
    return out.tick == tick;
  }

 private:
  std::array<LatestValue<TickSample>, kCapacity> slots_;
  std::atomic<std::uint64_t> published_{0};
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint32_t> epoch_{0};
  std::atomic<std::uint32_t> signal_{0};  // bumped with every publish; what waiters sleep on
};

}  // namespace haptic::runtime
