#pragma once
// The federation's view of this server's scene store (federation::ReplicatedScene): which of this
// site's items are marked across_sites, and the other sites' items applied here, each site's under
// an owner of its own (net::kRemoteSiteOwnerBit), so they ramp out as a lapsed session's do and
// never count against this site's sessions. Another site's item is checked here exactly as a
// client's would be (schema::to_object_spec with this site's limits); what fails is refused with
// the field named, and nothing of it is applied.

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "federation/item_replicator.hpp"
#include "net/scene_store.hpp"
#include "schema/scene_specs.hpp"

namespace haptic::app {

class FederatedScene final : public federation::ReplicatedScene {
 public:
  FederatedScene(net::SceneStore& store, schema::SceneLimits limits) : store_(store), limits_(std::move(limits)) {}

  std::uint64_t generation() const override { return store_.generation(); }
  std::vector<federation::LocalSharedItem> shared_items() const override;
  std::string describe(std::uint64_t id) const override;
  std::string put_remote(const federation::SharedItemState& item) override;
  void remove_remote(const std::string& site, std::uint64_t item) override;

  /// The scene owner another site's items are held under (kRemoteSiteOwnerBit set).
  std::uint64_t owner_of(const std::string& site);

 private:
  struct Applied {
    std::uint64_t local_id = 0;
    net::ItemKind kind = net::ItemKind::kObject;
  };

  net::SceneStore& store_;
  schema::SceneLimits limits_;
  std::mutex mutex_;
  std::map<std::string, std::uint64_t> owners_;                        // site → owner
  std::map<std::pair<std::string, std::uint64_t>, Applied> applied_;  // (site, its id) → here
};

}  // namespace haptic::app
