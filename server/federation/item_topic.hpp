#pragma once
// The federation's shared-scene topic (proto/haptic/dds/federation.idl, SharedItem): each site
// publishes the items its clients marked across_sites, and takes the other sites' (docs/
// federation.md, "Shared scene"). QoS: reliable, transient-local, keep last one per (site, item),
// so a site that joins late gets every live item, and the newest version of each is what counts.
// Writer liveliness is automatic with a lease (kItemLease): a site that stops or leaves the
// network loses its items at the others once its lease has run out.
//
// Off the loop (Cyclone's write and take allocate).

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <dds/dds.h>

#include "federation/dds_endpoint.hpp"

namespace haptic::federation {

inline constexpr const char* kItemTopic = "haptic_federation_items";

/// A site's items are lost at the others this long after its writer last made itself heard.
inline constexpr std::chrono::milliseconds kItemLease{1000};

/// The largest item description the topic carries (a 20,000-triangle mesh is ≈ 0.6 MB). Unit: bytes.
inline constexpr std::size_t kMaxItemBytes = 4u << 20;

enum class SharedItemKind : std::uint8_t { kObject = 0, kField = 1 };

/// One item as its owning site describes it.
struct SharedItemState {
  std::string site;           // the owning site (at most 64 characters)
  std::uint64_t item = 0;     // its id there
  std::uint64_t version = 0;  // its version there (1, 2, ...)
  SharedItemKind kind = SharedItemKind::kObject;
  std::string spec;           // haptic.v1.Object or haptic.v1.Field, protobuf binary
};

/// What happened to another site's item.
struct SharedItemEvent {
  enum class What {
    kPut,      // created or updated: `state` holds it
    kRemoved,  // its site removed it (disposed)
    kLost,     // its site's writer is gone (stopped, or its lease ran out)
  };
  What what = What::kPut;
  SharedItemState state;  // for kRemoved and kLost, only site and item
  /// For kPut and kRemoved: the site the writer speaks for (its partition, dds_endpoint's
  /// WriterSites), which must be state.site.
  std::string writer_site;
};

class ItemPublisher {
 public:
  /// In `site`'s partition (in_site_partition). Throws std::runtime_error naming what Cyclone
  /// refused.
  ItemPublisher(const Participant& participant, const std::string& site);
  ItemPublisher(const ItemPublisher&) = delete;
  ItemPublisher& operator=(const ItemPublisher&) = delete;

  /// Publishes (creates or replaces) one item; false, with error() saying why, when refused.
  bool put(const SharedItemState& item);
  /// Disposes one item at every site.
  bool remove(const std::string& site, std::uint64_t item);
  const std::string& error() const { return error_; }
  std::uint32_t matched_readers() const;

 private:
  Endpoint writer_;
  std::string error_;
};

class ItemSubscriber {
 public:
  explicit ItemSubscriber(const Participant& participant);
  ItemSubscriber(const ItemSubscriber&) = delete;
  ItemSubscriber& operator=(const ItemSubscriber&) = delete;

  /// Appends what happened to the other sites' items since the last take, oldest first (this
  /// participant's own writers never match: from_other_sites). Returns how many.
  std::size_t take(std::vector<SharedItemEvent>& out);
  std::uint32_t matched_writers() const;

 private:
  Endpoint reader_;
  WriterSites writers_;
};

}  // namespace haptic::federation
