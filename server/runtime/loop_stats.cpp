#include "runtime/loop_stats.hpp"

#include <algorithm>

namespace haptic::runtime {

double LatenessHistogram::bin_lower_edge_us(std::size_t bin) {
  if (bin < kFineBins) return static_cast<double>(bin);
  return static_cast<double>(kFineBins) + 100.0 * static_cast<double>(bin - kFineBins);
}

LatenessHistogram::LatenessHistogram(int window_s)
    : slot_count_(static_cast<std::size_t>(window_s < 1 ? 1 : window_s) + 1),
      slots_(std::make_unique<Slot[]>(slot_count_)) {}

LatenessSummary LatenessHistogram::summarize(std::int64_t now_ns) const {
  Counts counts;
  return summarize(now_ns, counts);
}

LatenessSummary LatenessHistogram::summarize(std::int64_t now_ns, Counts& counts) const {
  counts.fill(0);
  LatenessSummary summary;
  summary.window_s = static_cast<double>(window_s());
  const std::int64_t now_second = now_ns / kSlotNs;
  std::int64_t max_ns = 0;
  for (std::size_t s = 0; s < slot_count_; ++s) {
    const Slot& slot = slots_[s];
    const std::int64_t second = slot.second.load(std::memory_order_acquire);
    // Within the window: this second and the window_s before it (older slots wait to be reused).
    if (second < 0 || second > now_second ||
        second <= now_second - static_cast<std::int64_t>(slot_count_)) {
      continue;
    }
    for (std::size_t i = 0; i < kBins; ++i) {
      const std::uint64_t count = slot.bins[i].load(std::memory_order_acquire);
      counts[i] += count;
      summary.samples += count;
    }
    max_ns = std::max(max_ns, slot.max_ns.load(std::memory_order_relaxed));
  }
  summary.max_us = static_cast<double>(max_ns) / 1000.0;
  if (summary.samples == 0) return summary;
  auto percentile = [&](double q) {
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(summary.samples - 1));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBins; ++i) {
      seen += counts[i];
      if (seen > rank) return bin_lower_edge_us(i);
    }
    return bin_lower_edge_us(kBins - 1);
  };
  summary.p50_us = percentile(0.50);
  summary.p99_us = percentile(0.99);
  summary.p999_us = percentile(0.999);
  return summary;
}

}  // namespace haptic::runtime
