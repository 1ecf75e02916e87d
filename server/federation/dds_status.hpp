#pragma once
// What the federation's topics share over Cyclone's C API: the endpoints' matched counts, and
// taking every sample that arrived by loan.

#include <array>
#include <cstddef>
#include <cstdint>

#include <dds/dds.h>

namespace haptic::federation {

/// How many readers a writer (publication) or writers a reader has matched so far (discovery).
inline std::uint32_t matched_count(dds_entity_t entity, bool publication) {
  if (publication) {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(entity, &status) == DDS_RETCODE_OK ? status.current_count : 0;
  }
  dds_subscription_matched_status_t status{};
  return dds_get_subscription_matched_status(entity, &status) == DDS_RETCODE_OK ? status.current_count : 0;
}

/// Takes every sample the reader holds, in batches, by loan (Cyclone owns the samples' sequences
/// until the loan is returned): calls each(const Sample&, const dds_sample_info_t&) per sample,
/// invalid ones (no data: a disposal, a lost writer) included. Returns how many were taken.
template <class Sample, class Each>
std::size_t take_each(dds_entity_t reader, Each&& each) {
  constexpr std::size_t kBatch = 16;
  std::size_t taken = 0;
  for (;;) {
    std::array<void*, kBatch> pointers{};
    std::array<dds_sample_info_t, kBatch> infos{};
    const dds_return_t n = dds_take(reader, pointers.data(), infos.data(), kBatch, kBatch);
    if (n <= 0) break;
    for (dds_return_t i = 0; i < n; ++i) {
      each(*static_cast<const Sample*>(pointers[static_cast<std::size_t>(i)]), infos[static_cast<std::size_t>(i)]);
    }
    dds_return_loan(reader, pointers.data(), n);
    taken += static_cast<std::size_t>(n);
    if (static_cast<std::size_t>(n) < kBatch) break;
  }
  return taken;
}

}  // namespace haptic::federation
