#pragma once
// Counters the loop writes and other threads read: fixed-size, relaxed atomics, no locks
// (after MuJoCo's warning counters). The lateness histogram has 1 µs bins up to 1 ms, then 100 µs
// bins up to 100 ms; later wakes land in the last bin.

#include <array>
#include <atomic>
#include <cstdint>

namespace haptic::runtime {

struct LatenessSummary {
  std::uint64_t samples = 0;
  double p50_us = 0.0;
  double p99_us = 0.0;
  double p999_us = 0.0;
  double max_us = 0.0;
};

class LatenessHistogram {
 public:
  static constexpr std::size_t kFineBins = 1000;   // 1 µs each: [0, 1000) µs
  static constexpr std::size_t kCoarseBins = 990;  // 100 µs each: [1 ms, 100 ms)
  static constexpr std::size_t kBins = kFineBins + kCoarseBins + 1;

  /// On the loop.
  void record(std::int64_t lateness_ns) {
    const std::int64_t us = lateness_ns < 0 ? 0 : lateness_ns / 1000;
    std::size_t bin;
    if (us < static_cast<std::int64_t>(kFineBins)) {
      bin = static_cast<std::size_t>(us);
    } else {
      const std::int64_t coarse = (us - static_cast<std::int64_t>(kFineBins)) / 100;
      bin = coarse < static_cast<std::int64_t>(kCoarseBins) ? kFineBins + static_cast<std::size_t>(coarse)
                                                            : kBins - 1;
    }
    bins_[bin].fetch_add(1, std::memory_order_relaxed);
    std::int64_t seen = max_ns_.load(std::memory_order_relaxed);
    if (lateness_ns > seen) max_ns_.store(lateness_ns, std::memory_order_relaxed);  // single writer
  }

  /// Off the loop. Percentiles are bin lower edges (1 µs resolution below 1 ms).
  LatenessSummary summarize() const;

  /// Off the loop; races with record() only by losing a few samples.
  void reset();

 private:
  std::array<std::atomic<std::uint64_t>, kBins> bins_{};
  std::atomic<std::int64_t> max_ns_{0};
};

struct LoopCounters {
  std::atomic<std::uint64_t> ticks{0};
  std::atomic<std::uint64_t> overruns{0};          // periods missed because a tick ran late
  std::atomic<std::uint64_t> force_faults{0};      // non-finite forces replaced by zero
  std::atomic<std::uint64_t> force_saturations{0};
  std::atomic<std::uint64_t> device_errors{0};
  std::atomic<std::uint64_t> passivity_active_ticks{0};  // ticks the passivity controller damped
};

}  // namespace haptic::runtime
