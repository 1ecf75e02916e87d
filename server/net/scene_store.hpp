#pragma once
// The shared scene: every session's objects and fields, with ownership. Each change is validated
// in full before anything moves, applied under one lock, compiled and published to the loop as a
// new snapshot, so a request is applied whole or not at all.
//
// No change steps the force: a new item ramps in from the tick after it is created; a removed
// item stays in the compiled scene with its fade-out start tick until its force has ramped to
// zero, then compact() drops it (removed items are no longer addressable); an updated item keeps
// its id while its old version fades out and the new one fades in over the same ramp.

#include <grpcpp/support/status.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <variant>
#include <vector>

#include "engine/scene/compiled_scene.hpp"
#include "haptic/v1/scene.pb.h"
#include "engine/scene/scene_spec.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::net {

enum class ItemKind { kObject, kField };

/// The whole scene's budget (every session's items, fading ones included), and the shares of it
/// one session and the sessions of one host may hold, so one client cannot starve the rest (the
/// server's own scene, session 0, is exempt from the shares): 0 means none.
struct SceneBudget {
  std::uint64_t max_triangles = 0;
  std::uint64_t max_bytes = 0;  // Unit: bytes.
  std::uint64_t max_triangles_per_session = 0;
  std::uint64_t max_bytes_per_session = 0;
  std::uint64_t max_triangles_per_peer = 0;
  std::uint64_t max_bytes_per_peer = 0;
  /// The host a session was opened from (SessionRegistry::peer_of); needed for the per-host
  /// shares, none without them.
  std::function<std::string(std::uint64_t session_id)> host_of_session{};
};

/// What an item holds in memory.
struct ItemCost {
  std::uint64_t triangles = 0;
  std::uint64_t bytes = 0;  // Unit: bytes: the description, a mesh and its hierarchy.
};
ItemCost cost_of(const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec);

/// An item as its client described it (the request's message, defaults not filled in): what
/// GetScene reads back. Exactly one is set. Shared, so an update's fading copy costs nothing.
struct ItemSource {
  std::shared_ptr<const v1::Object> object;
  std::shared_ptr<const v1::Field> field;
};

/// A live item for read-back, in id order.
struct SceneEntry {
  std::uint64_t id = 0;
  std::uint64_t session_id = 0;  // 0: the server's own scene
  ItemSource source;
  std::uint64_t version_key = 0;  // changes with every update of the item
};

struct SceneCounts {
  std::uint32_t objects = 0;  // live (not fading)
  std::uint32_t fields = 0;
  std::uint32_t fading = 0;
};

class SceneStore {
 public:
  /// next_tick() tells the index of the next tick the loop will run (fade-outs begin there).
  /// period_s: the loop period (s), for the discrete impedance laws. ports: the device ports
  /// the loop evaluates every compiled scene at (>= 1).
  SceneStore(runtime::SceneExchange& exchange, std::function<std::int64_t()> next_tick,
             std::int64_t removal_ramp_ticks, std::uint32_t max_items_per_session,
             double period_s = 1e-3, double session_force_budget = 0.0, std::uint32_t ports = 1,
             SceneBudget budget = {});

  /// `source` is the message `spec` was made from (kept for read()).
  grpc::Status create(std::uint64_t session_id, ItemKind kind,
                      const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec,
                      std::uint64_t& id_out, ItemSource source = {});
  grpc::Status update(std::uint64_t session_id, ItemKind kind, std::uint64_t id,
                      const std::variant<engine::ObjectSpec, engine::FieldSpec>& spec,
                      ItemSource source = {});
  grpc::Status remove(std::uint64_t session_id, ItemKind kind, std::uint64_t id);

  /// Replaces all of the session's items (the old ones fade out). Ids in request order.
  /// `source` is the scene the specs were made from, item for item (kept for read()).
  grpc::Status replace_session_scene(std::uint64_t session_id,
                                     const std::vector<engine::ObjectSpec>& objects,
                                     const std::vector<engine::FieldSpec>& fields,
                                     std::vector<std::uint64_t>& object_ids,
                                     std::vector<std::uint64_t>& field_ids,
                                     const v1::Scene* source = nullptr);

  /// The live items (not fading out) as their clients described them, in id order: the
  /// session's own, or every session's (and the server's) with `all_sessions`.
  std::vector<SceneEntry> read(std::uint64_t session_id, bool all_sessions) const;

  /// A lockstep reset for `session_id`: every item goes at once (no ramp: no tick runs until the
  /// next step, and the run must start as the first did), ids count from 1 again, and the
  /// server's own scene (`objects`, `fields`, from `source`) is made again as at start, ramping
  /// in from tick 1. Refused (FAILED_PRECONDITION naming it, nothing changed) while another
  /// session holds live items (fading ones go). `restart` (the loop numbering its ticks from 1,
  /// fresh devices) runs under the store's lock once the check has passed, so no other session's
  /// change lands between the check, the restart and the new scene.
  grpc::Status reset(std::uint64_t session_id, const std::vector<engine::ObjectSpec>& objects,
                     const std::vector<engine::FieldSpec>& fields, const v1::Scene& source,
                     const std::function<void()>& restart);

  /// Starts the fade-out of everything the session owns (lease lost, session closed).
  std::size_t remove_session(std::uint64_t session_id);

  /// Drops items whose fade-out has finished; republishes if anything went. Returns how many.
  std::size_t compact();

  SceneCounts counts() const;

  /// Bumped by every snapshot published (any change, a compaction, a reset): a reader that saw
  /// another value reads the scene again.
  std::uint64_t generation() const;

  /// Energy exchanged with the device per item, as the loop has metered it (empty before the
  /// loop's first tick).
  std::vector<engine::ItemEnergyTotals> energy() const;

  /// The virtual masses as the loop has moved them (empty before the loop's first tick).
  std::vector<engine::ObjectMotion> motions() const;

 private:
  struct Item {
    engine::ItemMeta meta;
    ItemKind kind;
    std::variant<engine::ObjectSpec, engine::FieldSpec> spec;
    ItemSource source;
  };

  /// The live item `id` of `kind` that `session_id` may change: its own, or (to update) another
  /// session's shared object.
  grpc::Status find_owned(std::uint64_t session_id, ItemKind kind, std::uint64_t id,
                          Item*& item, bool to_update = false);
  std::uint32_t live_items_of(std::uint64_t session_id) const;
  /// OK if the scene can take `added` more (besides what it holds), else RESOURCE_EXHAUSTED
  /// naming the budget; `what` names the addition in the message.
  grpc::Status check_budget(const ItemCost& added, const std::string& what,
                            std::uint64_t session_id) const;
  /// replace_session_scene's work, under the lock.
  grpc::Status replace_locked(std::uint64_t session_id, const std::vector<engine::ObjectSpec>& objects,
                              const std::vector<engine::FieldSpec>& fields,
                              std::vector<std::uint64_t>& object_ids,
                              std::vector<std::uint64_t>& field_ids, const v1::Scene* source,
                              std::int64_t first_tick);
  void publish_locked();

  runtime::SceneExchange& exchange_;
  std::function<std::int64_t()> next_tick_;
  std::int64_t removal_ramp_ticks_;
  std::uint32_t max_items_per_session_;
  double period_s_;
  double session_force_budget_;
  std::uint32_t ports_;  // device ports each compiled scene is evaluated at
  SceneBudget budget_;

  mutable std::mutex mutex_;
  std::map<std::uint64_t, Item> items_;  // by id; ordered, so compilation is deterministic
  std::vector<Item> superseded_;         // old versions of updated items, fading out
  std::uint64_t next_id_ = 1;
  std::uint64_t next_version_key_ = 1;  // every version of every item gets its own
  std::uint64_t generation_ = 0;
  std::uint64_t run_ = 0;  // bumped by reset(): see engine::CompiledScene::run
};

}  // namespace haptic::net
