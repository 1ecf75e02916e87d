#include "runtime/loop_stats.hpp"

namespace haptic::runtime {
namespace {

double bin_lower_edge_us(std::size_t bin) {
  if (bin < LatenessHistogram::kFineBins) return static_cast<double>(bin);
  return static_cast<double>(LatenessHistogram::kFineBins) +
         100.0 * static_cast<double>(bin - LatenessHistogram::kFineBins);
}

}  // namespace

LatenessSummary LatenessHistogram::summarize() const {
  std::array<std::uint64_t, kBins> counts{};
  LatenessSummary summary;
  for (std::size_t i = 0; i < kBins; ++i) {
    counts[i] = bins_[i].load(std::memory_order_relaxed);
    summary.samples += counts[i];
  }
  summary.max_us = static_cast<double>(max_ns_.load(std::memory_order_relaxed)) / 1000.0;
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

void LatenessHistogram::reset() {
  for (auto& bin : bins_) bin.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

}  // namespace haptic::runtime
