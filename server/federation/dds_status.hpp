#pragma once
// What Cyclone's status calls say about a topic's endpoints, shared by the federation's topics.

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

}  // namespace haptic::federation
