#pragma once
// Counters the loop writes and other threads read: fixed-size, relaxed atomics, no locks
// (after MuJoCo's warning counters). The lateness histogram has 1 µs bins up to 1 ms, then 100 µs
// bins up to 100 ms; later wakes land in the last bin; it covers a sliding window of seconds.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

namespace haptic::runtime {

struct LatenessSummary {
  std::uint64_t samples = 0;
  double p50_us = 0.0;
  double p99_us = 0.0;
  double p999_us = 0.0;
  double max_us = 0.0;
  double window_s = 0.0;  // the span summarized: the last window_s whole seconds and this one
};

/// A histogram over a sliding window: one slot per second of the recording clock, the last
/// window_s + 1 of them kept, so a summary shows how the loop does now, not since it started (a
/// stall an hour ago has left it window_s seconds later). The writer clears a slot when it enters
/// a new second (~2,000 relaxed stores, about a microsecond, once a second); a summary taken during
/// that clear may miss that slot's samples, never count a sample twice.
class LatenessHistogram {
 public:
  static constexpr std::size_t kFineBins = 1000;   // 1 µs each: [0, 1000) µs
  static constexpr std::size_t kCoarseBins = 990;  // 100 µs each: [1 ms, 100 ms)
  static constexpr std::size_t kBins = kFineBins + kCoarseBins + 1;
  static constexpr int kDefaultWindowS = 10;

  explicit LatenessHistogram(int window_s = kDefaultWindowS);

  /// One writer. `now_ns`: the recording thread's clock (monotonic ns), which picks the slot.
  void record(std::int64_t lateness_ns, std::int64_t now_ns) {
    const std::int64_t second = now_ns / kSlotNs;
    Slot& slot = slots_[static_cast<std::size_t>(second) % slot_count_];
    if (slot.second.load(std::memory_order_relaxed) != second) {
      slot.second.store(-1, std::memory_order_release);  // readers skip it while it is cleared
      for (auto& bin : slot.bins) bin.store(0, std::memory_order_relaxed);
      slot.max_ns.store(0, std::memory_order_relaxed);
      slot.second.store(second, std::memory_order_release);
    }
    // Release: a reader that counts this sample also sees what the recording thread did before
    // it (the tick it belongs to, counted in LoopCounters::ticks).
    slot.bins[bin_of(lateness_ns)].fetch_add(1, std::memory_order_release);
    if (lateness_ns > slot.max_ns.load(std::memory_order_relaxed)) {
      slot.max_ns.store(lateness_ns, std::memory_order_relaxed);  // single writer
    }
  }

  using Counts = std::array<std::uint64_t, kBins>;

  /// Off the recording thread: the window ending at `now_ns` (same clock as record's).
  /// Percentiles are bin lower edges (1 µs resolution below 1 ms).
  LatenessSummary summarize(std::int64_t now_ns) const;
  /// The same window bin by bin (what summarize reads): `counts` is filled in; returns its
  /// summary. Reads only what record() wrote; costs the recording thread nothing.
  LatenessSummary summarize(std::int64_t now_ns, Counts& counts) const;

  /// Bin `bin`'s lower edge and width. Unit: µs.
  static double bin_lower_edge_us(std::size_t bin);
  static double bin_width_us(std::size_t bin) { return bin < kFineBins ? 1.0 : 100.0; }

  int window_s() const { return static_cast<int>(slot_count_) - 1; }

 private:
  static constexpr std::int64_t kSlotNs = 1'000'000'000;
  struct Slot {
    std::array<std::atomic<std::uint64_t>, kBins> bins{};
    std::atomic<std::int64_t> max_ns{0};
    std::atomic<std::int64_t> second{-1};  // the second it holds; -1 none (or being cleared)
  };

  static std::size_t bin_of(std::int64_t lateness_ns) {
    const std::int64_t us = lateness_ns < 0 ? 0 : lateness_ns / 1000;
    if (us < static_cast<std::int64_t>(kFineBins)) return static_cast<std::size_t>(us);
    const std::int64_t coarse = (us - static_cast<std::int64_t>(kFineBins)) / 100;
    return coarse < static_cast<std::int64_t>(kCoarseBins) ? kFineBins + static_cast<std::size_t>(coarse)
                                                         : kBins - 1;
  }

  std::size_t slot_count_;
  std::unique_ptr<Slot[]> slots_;
};

struct LoopCounters {
  std::atomic<std::uint64_t> ticks{0};
  std::atomic<std::uint64_t> overruns{0};          // periods missed because a tick ran late
  std::atomic<std::uint64_t> force_faults{0};      // non-finite forces replaced by zero
  std::atomic<std::uint64_t> force_saturations{0};
  std::atomic<std::uint64_t> device_errors{0};
  std::atomic<std::uint64_t> passivity_active_ticks{0};  // ticks the passivity controller damped
  std::atomic<std::uint64_t> robot_wrenches_refused{0};  // non-finite ROS 2 wrenches the loop refused
};

}  // namespace haptic::runtime
