#pragma once
// The shared scene across sites (docs/federation.md, "Shared scene"): a thread that publishes
// this site's items marked across_sites on the item topic as they are created, updated and
// removed, and applies the other sites' to this site's scene, where each is compiled and rendered
// at this site's own loop rate (004 ch. 5's local models, one level up). A site that leaves or
// stops has its items removed here once its writer's lease has run out, and they ramp out as a
// lapsed session's do.
//
// The scene is reached through ReplicatedScene, which the server implements over its scene store;
// the replicator knows DDS, not the store.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "federation/dds_participant.hpp"
#include "federation/item_topic.hpp"
#include "federation/log_limiter.hpp"

namespace haptic::federation {

/// One of this site's items that a client marked across_sites.
struct LocalSharedItem {
  std::uint64_t id = 0;
  SharedItemKind kind = SharedItemKind::kObject;
  std::uint64_t version_key = 0;  // changes with every update of the item
};

class ReplicatedScene {
 public:
  virtual ~ReplicatedScene() = default;
  /// Changes with every change of the scene (a cheap check before shared_items()).
  virtual std::uint64_t generation() const = 0;
  /// This site's own live items marked across_sites (never another site's copies), by id.
  virtual std::vector<LocalSharedItem> shared_items() const = 0;
  /// Item `id` as its client described it, protobuf binary; "" if it is gone.
  virtual std::string describe(std::uint64_t id) const = 0;
  /// Another site's item, created here or updated: "" or why it was refused, naming the field
  /// ("object.impedance.stiffness: must be …").
  virtual std::string put_remote(const SharedItemState& item) = 0;
  /// Another site's item goes (ramping out); nothing if it is not here.
  virtual void remove_remote(const std::string& site, std::uint64_t item) = 0;
};

struct ReplicatorOptions {
  std::string site;
  DomainOptions domain;
  std::chrono::milliseconds period{10};  // how often the scene is compared and the topic taken
  /// Where refusals and sites' comings and goings are reported (one line each); may be empty.
  std::function<void(const std::string&)> log;
  /// Another site's refused items, and its items ramping out, are logged once in this long per
  /// site (the rest counted, then summarized: LogLimiter).
  std::chrono::milliseconds log_window{10000};
};

class ItemReplicator {
 public:
  /// Joins the domain and makes the topic's writer and reader (off the loop). Throws
  /// std::runtime_error naming what was refused; a writer that DDS Security's permissions refuse
  /// (an observer) leaves the replicator receiving only, and the log says so.
  ItemReplicator(const ReplicatorOptions& options, ReplicatedScene& scene);
  /// The same on a participant the caller holds (a hapticd's one, which its relay made): one
  /// participant per site, so one identity and one set of ports. `participant` outlives this.
  ItemReplicator(const ReplicatorOptions& options, ReplicatedScene& scene, const Participant& participant);
  ~ItemReplicator();
  ItemReplicator(const ItemReplicator&) = delete;
  ItemReplicator& operator=(const ItemReplicator&) = delete;

  void start();
  void stop();

  /// One round, for tests that step it: publish what changed here, apply what arrived (at `now`,
  /// for the log's rate limit).
  void poll();
  void poll(std::chrono::steady_clock::time_point now);

  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::uint64_t applied() const { return applied_.load(std::memory_order_relaxed); }
  std::uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }

 private:
  void open(const Participant& participant);
  void publish_changes();
  void apply_arrivals(std::chrono::steady_clock::time_point now);
  void log(const std::string& line) const;
  /// `line` under the rate limit of `key` (a site and what happened).
  void log_limited(const std::string& key, const std::string& line, std::chrono::steady_clock::time_point now);

  struct Published {
    std::uint64_t version_key = 0;
    std::uint64_t version = 0;  // what the topic says
  };

  ReplicatorOptions options_;
  ReplicatedScene& scene_;
  std::unique_ptr<Participant> participant_;  // ours, when none was given
  std::unique_ptr<ItemPublisher> writer_;  // null where this site's permissions refuse it
  std::string refusal_;                    // why, then
  std::unique_ptr<ItemSubscriber> reader_;
  std::uint64_t seen_generation_ = ~std::uint64_t{0};
  std::map<std::uint64_t, Published> published_items_;  // by local id
  std::vector<SharedItemEvent> events_;                  // scratch
  LogLimiter limiter_;
  std::vector<std::string> log_lines_;                   // scratch
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> applied_{0};
  std::atomic<std::uint64_t> refused_{0};
};

}  // namespace haptic::federation
