#pragma once
// A single-slot mailbox for a small trivially copyable value, written off the loop and read on it
// without locks (a seqlock). Writers are serialised by the caller; the reader retries while a write
// is in progress, which lasts a few nanoseconds.

#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace haptic::runtime {

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  LatestValue() { store(T{}); }
  explicit LatestValue(const T& initial) { store(initial); }

  /// Off the loop. Callers must not call store() concurrently with each other.
  void store(const T& value) {
    const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
    std::atomic_thread_fence(std::memory_order_release);
    copy_in(value);
    sequence_.store(seq + 2, std::memory_order_release);
  }

  /// On the loop. Returns the newest complete value.
  T load() const {
    T out;
    for (;;) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before & 1u) continue;
      copy_out(out);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) == before) return out;
    }
  }

  /// Changes every time a value is stored; lets a reader skip an unchanged value.
  std::uint64_t version() const { return sequence_.load(std::memory_order_acquire); }

 private:
  // Word-wise relaxed copies keep the racy read defined behaviour under the C++ memory model
  // (a byte at a time cost the loop ~120 stores per published sample).
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);

  void copy_in(const T& value) {
    std::uint64_t words[kWords] = {};
    std::memcpy(words, &value, sizeof(T));
    for (std::size_t i = 0; i < kWords; ++i) storage_[i].store(words[i], std::memory_order_relaxed);
  }
  void copy_out(T& value) const {
    std::uint64_t words[kWords];
    for (std::size_t i = 0; i < kWords; ++i) words[i] = storage_[i].load(std::memory_order_relaxed);
    std::memcpy(&value, words, sizeof(T));
  }

  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::uint64_t> storage_[kWords]{};
};

}  // namespace haptic::runtime
