#include "net/scene_store.hpp"

#include <algorithm>
#include <map>
#include <string>

#include "haptic/io/session_id.hpp"

namespace haptic::net {
namespace {

const char* kind_name(ItemKind kind) { return kind == ItemKind::kObject ? "object" : "field"; }

bool is_live(const engine::ItemMeta& meta) { return meta.fade_begin_tick == engine::kNeverTick; }

/// A new item that ramps in from `tick`.
engine::ItemMeta appearing(std::uint64_t session_id, std::uint64_t id, std::int64_t tick,
                           std::uint64_t version_key) {
  engine::ItemMeta meta;
  meta.session_id = session_id;
  meta.id = id;
  meta.version_key = version_key;
  meta.ramps.appear_tick = tick;
  return meta;
}

}  // namespace

ItemCost cost_of(const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec) {
  ItemCost cost;
  cost.bytes = sizeof(spec);
  const auto* object = std::get_if<engine::ObjectSpec>(&spec);
  const auto* mesh = object ? std::get_if<engine::MeshShapeSpec>(&object->shape) : nullptr;
  if (mesh != nullptr && mesh->model) {
    const engine::Mesh& m = mesh->model->mesh;
    cost.triangles = m.triangles.size();
    cost.bytes += sizeof(engine::MeshModel) + m.vertices_O.capacity() * sizeof(engine::Vec3) +
                  m.triangles.capacity() * sizeof(m.triangles[0]) + mesh->model->bvh.memory_bytes();
  }
  return cost;
}

grpc::Status SceneStore::check_budget(const ItemCost& added, const std::string& what,
                                      std::uint64_t session_id) const {
  const bool per_peer = session_id != 0 && budget_.host_of_session &&
                        (budget_.max_triangles_per_peer > 0 || budget_.max_bytes_per_peer > 0);
  const std::string host = per_peer ? budget_.host_of_session(session_id) : std::string();
  std::map<std::uint64_t, std::string> hosts;  // each session's, looked up once
  const auto same_host = [&](std::uint64_t owner) {
    if (!per_peer || owner == 0) return false;
    auto found = hosts.find(owner);
    if (found == hosts.end()) found = hosts.emplace(owner, budget_.host_of_session(owner)).first;
    return found->second == host;
  };
  ItemCost held, held_by_session, held_by_host;
  const auto add = [&](const Item& item) {
    const ItemCost cost = cost_of(item.spec);
    held.triangles += cost.triangles;
    held.bytes += cost.bytes;
    if (session_id != 0 && item.meta.session_id == session_id) {
      held_by_session.triangles += cost.triangles;
      held_by_session.bytes += cost.bytes;
    }
    if (same_host(item.meta.session_id)) {
      held_by_host.triangles += cost.triangles;
      held_by_host.bytes += cost.bytes;
    }
  };
  for (const auto& [id, item] : items_) add(item);
  for (const Item& item : superseded_) add(item);
  if (budget_.max_triangles > 0 && added.triangles > 0 &&
      held.triangles + added.triangles > budget_.max_triangles) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            what + ": " + std::to_string(added.triangles) + " more triangles would bring the scene "
                "(every session's, fading items included) to " +
                std::to_string(held.triangles + added.triangles) + ", over max_scene_triangles (" +
                std::to_string(budget_.max_triangles) + ")"};
  }
  if (budget_.max_bytes > 0 && held.bytes + added.bytes > budget_.max_bytes) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            what + ": " + std::to_string(added.bytes) + " more bytes would bring the scene "
                "(every session's, fading items included) to " +
                std::to_string(held.bytes + added.bytes) + " bytes, over max_scene_bytes (" +
                std::to_string(budget_.max_bytes) + ")"};
  }
  // The shares: what one host's sessions, then what one session, may hold of the whole.
  const auto over_share = [&](std::uint64_t limit, std::uint64_t add_amount, std::uint64_t holding,
                              const char* unit, const std::string& whose, const char* field) {
    return grpc::Status{grpc::StatusCode::RESOURCE_EXHAUSTED,
                        what + ": " + std::to_string(add_amount) + " more " + unit + " would bring " +
                            whose + " (fading items included) to " +
                            std::to_string(holding + add_amount) + ", over " + field + " (" +
                            std::to_string(limit) + ")"};
  };
  const std::string host_items = "the items of the sessions from " + host;
  if (per_peer && budget_.max_triangles_per_peer > 0 && added.triangles > 0 &&
      held_by_host.triangles + added.triangles > budget_.max_triangles_per_peer) {
    return over_share(budget_.max_triangles_per_peer, added.triangles, held_by_host.triangles,
                      "triangles", host_items, "max_scene_triangles_per_peer");
  }
  if (per_peer && budget_.max_bytes_per_peer > 0 &&
      held_by_host.bytes + added.bytes > budget_.max_bytes_per_peer) {
    return over_share(budget_.max_bytes_per_peer, added.bytes, held_by_host.bytes, "bytes",
                      host_items, "max_scene_bytes_per_peer");
  }
  if (session_id != 0 && budget_.max_triangles_per_session > 0 && added.triangles > 0 &&
      held_by_session.triangles + added.triangles > budget_.max_triangles_per_session) {
    return over_share(budget_.max_triangles_per_session, added.triangles, held_by_session.triangles,
                      "triangles", "this session's items", "max_scene_triangles_per_session");
  }
  if (session_id != 0 && budget_.max_bytes_per_session > 0 &&
      held_by_session.bytes + added.bytes > budget_.max_bytes_per_session) {
    return over_share(budget_.max_bytes_per_session, added.bytes, held_by_session.bytes, "bytes",
                      "this session's items", "max_scene_bytes_per_session");
  }
  return grpc::Status::OK;
}

SceneStore::SceneStore(runtime::SceneExchange& exchange, std::function<std::int64_t()> next_tick,
                       std::int64_t removal_ramp_ticks, std::uint32_t max_items_per_session,
                       double period_s, double session_force_budget, std::uint32_t ports,
                       SceneBudget budget)
    : exchange_(exchange),
      next_tick_(std::move(next_tick)),
      removal_ramp_ticks_(removal_ramp_ticks < 1 ? 1 : removal_ramp_ticks),
      max_items_per_session_(max_items_per_session),
      period_s_(period_s),
      session_force_budget_(session_force_budget),
      ports_(ports < 1 ? 1 : ports),
      budget_(budget) {}

std::uint32_t SceneStore::live_items_of(std::uint64_t session_id) const {
  std::uint32_t count = 0;
  for (const auto& [id, item] : items_) {
    if (item.meta.session_id == session_id && is_live(item.meta)) ++count;
  }
  return count;
}

grpc::Status SceneStore::find_owned(std::uint64_t session_id, ItemKind kind, std::uint64_t id,
                                    Item*& item, bool to_update) {
  auto it = items_.find(id);
  if (it == items_.end() || it->second.kind != kind || !is_live(it->second.meta)) {
    return {grpc::StatusCode::NOT_FOUND,
            std::string("id: no ") + kind_name(kind) + " with id " + std::to_string(id)};
  }
  const auto* object = std::get_if<engine::ObjectSpec>(&it->second.spec);
  const bool shared = object != nullptr && object->shared;
  if (it->second.meta.session_id != session_id && !(to_update && shared)) {
    return {grpc::StatusCode::PERMISSION_DENIED,
            std::string("id: ") + kind_name(kind) + " " + std::to_string(id) +
                (shared ? " is shared, but only its owner may delete it"
                        : " belongs to another session")};
  }
  item = &it->second;
  return grpc::Status::OK;
}

grpc::Status SceneStore::create(std::uint64_t session_id, ItemKind kind,
                                const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec,
                                std::uint64_t& id_out, ItemSource source) {
  std::lock_guard lock(mutex_);
  if (live_items_of(session_id) >= max_items_per_session_) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            "session already has " + std::to_string(max_items_per_session_) +
                " objects and fields (max_objects_per_session)"};
  }
  if (auto status = check_budget(cost_of(spec), kind_name(kind), session_id); !status.ok()) return status;
  id_out = next_id_++;
  items_.emplace(id_out, Item{appearing(session_id, id_out, next_tick_(), next_version_key_++),
                              kind, spec, std::move(source)});
  publish_locked();
  return grpc::Status::OK;
}

grpc::Status SceneStore::update(std::uint64_t session_id, ItemKind kind, std::uint64_t id,
                                const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec,
                                ItemSource source) {
  std::lock_guard lock(mutex_);
  Item* item = nullptr;
  if (auto status = find_owned(session_id, kind, id, item, true); !status.ok()) return status;
  // The old version stays held while it fades out: the new one comes on top.
  if (auto status = check_budget(cost_of(spec), kind_name(kind), session_id); !status.ok()) return status;
  if (item->meta.session_id != session_id) {
    // Another session updates a shared object: it stays shared, and its owner's.
    const auto* updated = std::get_if<engine::ObjectSpec>(&spec);
    if (updated == nullptr || !updated->shared) {
      return {grpc::StatusCode::PERMISSION_DENIED,
              "object.shared: only the owner may make a shared object private"};
    }
  }
  // Cross-fade (see engine::ItemRamp): the new version fades in from `now`, and every older
  // version of this item, the current one included, fades out against it.
  const std::int64_t now = next_tick_();
  superseded_.push_back(*item);
  std::vector<engine::ItemMeta*> versions;  // oldest first: the list keeps update order
  for (Item& old : superseded_) {
    if (old.meta.id == id) versions.push_back(&old.meta);
  }
  if (versions.size() > engine::ItemRamp::kMaxSuperseded) {
    // Updates faster than the ramp: the oldest version is dropped and the next-oldest takes over
    // its share (its fade-in is treated as complete). The force steps by the dropped version's
    // remaining share of the difference between the two — small, as that share has been fading.
    versions[1]->ramps.appear_tick = engine::kAlwaysTick;
    const std::uint64_t dropped_id = id;
    const auto oldest = std::find_if(superseded_.begin(), superseded_.end(),
                                     [&](const Item& old) { return old.meta.id == dropped_id; });
    superseded_.erase(oldest);
    versions.clear();
    for (Item& old : superseded_) {
      if (old.meta.id == id) versions.push_back(&old.meta);
    }
  }
  for (engine::ItemMeta* version : versions) {
    for (std::int64_t& at : version->ramps.superseded_at) {
      if (at == engine::kNeverTick) {
        at = now;
        break;
      }
    }
  }
  item->spec = spec;
  item->source = std::move(source);
  item->meta.ramps = engine::ItemRamp{};
  item->meta.ramps.appear_tick = now;
  item->meta.version_key = next_version_key_++;
  publish_locked();
  return grpc::Status::OK;
}

grpc::Status SceneStore::remove(std::uint64_t session_id, ItemKind kind, std::uint64_t id) {
  std::lock_guard lock(mutex_);
  Item* item = nullptr;
  if (auto status = find_owned(session_id, kind, id, item); !status.ok()) return status;
  item->meta.fade_begin_tick = next_tick_();
  publish_locked();
  return grpc::Status::OK;
}

grpc::Status SceneStore::replace_session_scene(std::uint64_t session_id,
                                               const std::vector<engine::ObjectSpec>& objects,
                                               const std::vector<engine::FieldSpec>& fields,
                                               std::vector<std::uint64_t>& object_ids,
                                               std::vector<std::uint64_t>& field_ids,
                                               const v1::Scene* source) {
  std::lock_guard lock(mutex_);
  return replace_locked(session_id, objects, fields, object_ids, field_ids, source, next_tick_());
}

grpc::Status SceneStore::replace_locked(std::uint64_t session_id,
                                        const std::vector<engine::ObjectSpec>& objects,
                                        const std::vector<engine::FieldSpec>& fields,
                                        std::vector<std::uint64_t>& object_ids,
                                        std::vector<std::uint64_t>& field_ids, const v1::Scene* source,
                                        std::int64_t first_tick) {
  if (objects.size() + fields.size() > max_items_per_session_) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            "scene: " + std::to_string(objects.size() + fields.size()) +
                " objects and fields exceed max_objects_per_session (" +
                std::to_string(max_items_per_session_) + ")"};
  }
  ItemCost added;  // the session's old items stay held while they fade out
  for (const auto& object : objects) {
    const ItemCost cost = cost_of(object);
    added.triangles += cost.triangles;
    added.bytes += cost.bytes;
  }
  for (const auto& field : fields) added.bytes += cost_of(field).bytes;
  if (auto status = check_budget(added, "scene", session_id); !status.ok()) return status;
  const std::int64_t fade_begin = first_tick;
  for (auto& [id, item] : items_) {
    if (item.meta.session_id == session_id && is_live(item.meta)) {
      item.meta.fade_begin_tick = fade_begin;
    }
  }
  object_ids.clear();
  field_ids.clear();
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::uint64_t id = next_id_++;
    ItemSource described;
    if (source != nullptr) described.object = std::make_shared<const v1::Object>(source->objects(static_cast<int>(i)));
    items_.emplace(id, Item{appearing(session_id, id, fade_begin, next_version_key_++),
                            ItemKind::kObject, objects[i], std::move(described)});
    object_ids.push_back(id);
  }
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::uint64_t id = next_id_++;
    ItemSource described;
    if (source != nullptr) described.field = std::make_shared<const v1::Field>(source->fields(static_cast<int>(i)));
    items_.emplace(id, Item{appearing(session_id, id, fade_begin, next_version_key_++),
                            ItemKind::kField, fields[i], std::move(described)});
    field_ids.push_back(id);
  }
  publish_locked();
  return grpc::Status::OK;
}

grpc::Status SceneStore::reset(std::uint64_t session_id, const std::vector<engine::ObjectSpec>& objects,
                               const std::vector<engine::FieldSpec>& fields, const v1::Scene& source,
                               const std::function<void()>& restart) {
  std::lock_guard lock(mutex_);
  // Another session's live items stand in the way; what is fading out was removed already.
  std::map<std::uint64_t, std::uint32_t> others;  // session -> live items it holds
  for (const auto& [id, item] : items_) {
    const std::uint64_t owner = item.meta.session_id;
    if (owner != session_id && owner != 0 && is_live(item.meta)) ++others[owner];
  }
  if (!others.empty()) {
    const auto& [other, count] = *others.begin();
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "session " + io::format_session_id(other) + " holds " + std::to_string(count) +
                " objects and fields; a reset would take them from under it: close it or remove "
                "them first"};
  }
  restart();
  items_.clear();
  superseded_.clear();
  next_id_ = 1;
  ++run_;  // the loop carries nothing from the old scenes into the new ones
  std::vector<std::uint64_t> object_ids, field_ids;
  return replace_locked(0, objects, fields, object_ids, field_ids, &source, 1);
}

std::size_t SceneStore::remove_session(std::uint64_t session_id) {
  std::lock_guard lock(mutex_);
  const std::int64_t fade_begin = next_tick_();
  std::size_t count = 0;
  for (auto& [id, item] : items_) {
    if (item.meta.session_id == session_id && is_live(item.meta)) {
      item.meta.fade_begin_tick = fade_begin;
      ++count;
    }
  }
  if (count > 0) publish_locked();
  return count;
}

std::size_t SceneStore::compact() {
  std::lock_guard lock(mutex_);
  const std::int64_t now = next_tick_();
  std::size_t removed = 0;
  for (auto it = items_.begin(); it != items_.end();) {
    const std::int64_t begin = it->second.meta.fade_begin_tick;
    if (begin != engine::kNeverTick && now > begin + removal_ramp_ticks_) {
      it = items_.erase(it);
      ++removed;
    } else {
      ++it;
    }
  }
  // A superseded version is gone once any of its fade-outs has run its course.
  const auto finished = [&](const Item& item) {
    for (const std::int64_t at : item.meta.ramps.superseded_at) {
      if (at != engine::kNeverTick && now > at + removal_ramp_ticks_) return true;
    }
    return item.meta.fade_begin_tick != engine::kNeverTick &&
           now > item.meta.fade_begin_tick + removal_ramp_ticks_;
  };
  const std::size_t superseded_before = superseded_.size();
  superseded_.erase(std::remove_if(superseded_.begin(), superseded_.end(), finished),
                    superseded_.end());
  removed += superseded_before - superseded_.size();
  if (removed > 0) publish_locked();
  exchange_.reclaim();
  return removed;
}

std::vector<SceneEntry> SceneStore::read(std::uint64_t session_id, bool all_sessions) const {
  std::lock_guard lock(mutex_);
  std::vector<SceneEntry> entries;
  for (const auto& [id, item] : items_) {
    if (!is_live(item.meta) || (!all_sessions && item.meta.session_id != session_id)) continue;
    entries.push_back(SceneEntry{id, item.meta.session_id, item.source, item.meta.version_key});
  }
  return entries;
}

std::uint64_t SceneStore::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

SceneCounts SceneStore::counts() const {
  std::lock_guard lock(mutex_);
  SceneCounts counts;
  counts.fading = static_cast<std::uint32_t>(superseded_.size());
  for (const auto& [id, item] : items_) {
    if (!is_live(item.meta)) {
      ++counts.fading;
    } else if (item.kind == ItemKind::kObject) {
      ++counts.objects;
    } else {
      ++counts.fields;
    }
  }
  return counts;
}

std::vector<engine::ItemEnergyTotals> SceneStore::energy() const {
  std::vector<engine::ItemEnergyTotals> out;
  exchange_.with_adopted([&](const engine::CompiledScene& scene) { out = engine::energy_totals(scene); });
  return out;
}

std::vector<engine::ObjectMotion> SceneStore::motions() const {
  std::vector<engine::ObjectMotion> out;
  exchange_.with_adopted([&](const engine::CompiledScene& scene) { out = engine::object_motions(scene); });
  return out;
}

void SceneStore::publish_locked() {
  engine::SceneDescription description;
  const auto add = [&](const Item& item) {
    if (const auto* object = std::get_if<engine::ObjectSpec>(&item.spec)) {
      description.objects.push_back(engine::ObjectEntry{item.meta, *object});
    } else {
      description.fields.push_back(
          engine::FieldEntry{item.meta, std::get<engine::FieldSpec>(item.spec)});
    }
  };
  for (const auto& [id, item] : items_) add(item);
  for (const Item& item : superseded_) add(item);
  engine::CompiledScene compiled = engine::compile_scene(description, removal_ramp_ticks_, ++generation_,
                                                         period_s_, session_force_budget_, ports_);
  compiled.run = run_;
  exchange_.publish(std::make_unique<const engine::CompiledScene>(std::move(compiled)));
}

}  // namespace haptic::net
