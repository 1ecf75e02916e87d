#pragma once
// A bounded single-producer single-consumer queue of States: the receive thread pushes (a copy and
// a release store; a full queue refuses and the caller counts a drop), the writer pops in batches.
// Sized once, at start. One producer at a time: the UdpLink calls its taps under its own lock.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "haptic/types.hpp"

namespace haptic::detail {

class SampleQueue {
 public:
  explicit SampleQueue(std::size_t capacity) : slots_(capacity) {}

  /// Producer. False when full (nothing is stored).
  bool push(const State& state) noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == slots_.size()) return false;
    slots_[tail % slots_.size()] = state;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer. Appends up to `max` States to `out` (cleared first); how many.
  std::size_t pop(std::vector<State>& out, std::size_t max) {
    out.clear();
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    const std::uint64_t n = std::min<std::uint64_t>(tail - head, max);
    for (std::uint64_t i = 0; i < n; ++i) out.push_back(slots_[(head + i) % slots_.size()]);
    head_.store(head + n, std::memory_order_release);
    return n;
  }

  std::size_t capacity() const noexcept { return slots_.size(); }

  bool empty() const noexcept {
    return tail_.load(std::memory_order_acquire) == head_.load(std::memory_order_acquire);
  }

 private:
  std::vector<State> slots_;
  // Counts of pushes and pops, never wrapped (2^64 samples); each on its own cache line.
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
};

}  // namespace haptic::detail
