#include "app/federated_scene.hpp"

#include <memory>

#include "net/session_registry.hpp"
#include "runtime/shared_masses.hpp"

namespace haptic::app {

namespace {

bool from_another_site(std::uint64_t owner) { return (owner & net::kRemoteSiteOwnerBit) != 0; }

}  // namespace

std::vector<federation::LocalSharedItem> FederatedScene::shared_items() const {
  std::vector<federation::LocalSharedItem> items;
  for (const net::SceneEntry& entry : store_.read(0, true)) {
    if (from_another_site(entry.session_id)) continue;  // never echoed back
    if (entry.source.object && entry.source.object->across_sites()) {
      items.push_back({entry.id, federation::SharedItemKind::kObject, entry.version_key});
    } else if (entry.source.field && entry.source.field->across_sites()) {
      items.push_back({entry.id, federation::SharedItemKind::kField, entry.version_key});
    }
  }
  return items;
}

std::string FederatedScene::describe(std::uint64_t id) const {
  for (const net::SceneEntry& entry : store_.read(0, true)) {
    if (entry.id != id) continue;
    if (entry.source.object) return entry.source.object->SerializeAsString();
    if (entry.source.field) return entry.source.field->SerializeAsString();
  }
  return {};
}

std::uint64_t FederatedScene::owner_of(const std::string& site) {
  const auto [it, added] = owners_.try_emplace(site, net::kRemoteSiteOwnerBit | (owners_.size() + 1));
  return it->second;
}

std::string FederatedScene::put_remote(const federation::SharedItemState& item) {
  std::lock_guard lock(mutex_);
  const std::uint64_t owner = owner_of(item.site);
  std::variant<engine::ObjectSpec, engine::FieldSpec> spec;
  net::ItemSource source;
  net::ItemKind kind = net::ItemKind::kObject;
  if (item.kind == federation::SharedItemKind::kObject) {
    auto object = std::make_shared<v1::Object>();
    if (!object->ParseFromString(item.spec)) return "spec: not a haptic.v1.Object";
    engine::ObjectSpec converted;
    if (std::string error = schema::to_object_spec(*object, "object", limits_, converted); !error.empty()) return error;
    // Only its site changes it: here it is no session's to update.
    converted.shared = false;
    // A mass shared across sites keeps its key from its site: this copy couples to that one's.
    converted.origin_site = engine::site_key(item.site);
    converted.origin_id = item.item;
    spec = std::move(converted);
    source.object = std::move(object);
  } else {
    auto field = std::make_shared<v1::Field>();
    if (!field->ParseFromString(item.spec)) return "spec: not a haptic.v1.Field";
    engine::FieldSpec converted;
    if (std::string error = schema::to_field_spec(*field, "field", limits_, converted); !error.empty()) return error;
    spec = std::move(converted);
    source.field = std::move(field);
    kind = net::ItemKind::kField;
  }
  const auto key = std::make_pair(item.site, item.item);
  const auto found = applied_.find(key);
  if (found != applied_.end() && found->second.kind == kind) {
    const grpc::Status status = store_.update(owner, kind, found->second.local_id, spec, source);
    if (status.ok()) return {};
    if (status.error_code() != grpc::StatusCode::NOT_FOUND) return status.error_message();
  } else if (found != applied_.end()) {
    // The same id now names an item of the other kind: the old one goes, the new one comes.
    (void)store_.remove(owner, found->second.kind, found->second.local_id);
  }
  std::uint64_t id = 0;
  const grpc::Status status = store_.create(owner, kind, spec, id, source);
  if (!status.ok()) {
    applied_.erase(key);
    return status.error_message();
  }
  applied_[key] = Applied{id, kind};
  return {};
}

void FederatedScene::remove_remote(const std::string& site, std::uint64_t item) {
  std::lock_guard lock(mutex_);
  const auto found = applied_.find(std::make_pair(site, item));
  if (found == applied_.end()) return;
  (void)store_.remove(owner_of(site), found->second.kind, found->second.local_id);
  applied_.erase(found);
}

}  // namespace haptic::app
