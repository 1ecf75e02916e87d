#include "federation/item_replicator.hpp"

#include <set>

namespace haptic::federation {

ItemReplicator::ItemReplicator(const ReplicatorOptions& options, ReplicatedScene& scene)
    : options_(options),
      scene_(scene),
      participant_(std::make_unique<Participant>(options.domain)),
      limiter_(options.log_window) {
  open(*participant_);
}

ItemReplicator::ItemReplicator(const ReplicatorOptions& options, ReplicatedScene& scene, const Participant& participant)
    : options_(options), scene_(scene), limiter_(options.log_window) {
  open(participant);
}

void ItemReplicator::open(const Participant& participant) {
  reader_ = std::make_unique<ItemSubscriber>(participant);
  try {
    writer_ = std::make_unique<ItemPublisher>(participant, options_.site);
  } catch (const std::runtime_error& error) {
    // Under DDS Security an observer's permissions refuse the writer: the site still gets the
    // others' items, and says once why its own are not shared.
    refusal_ = error.what();
    log("federation: this site shares no items (" + refusal_ + "); it still receives the other sites'");
  }
}

ItemReplicator::~ItemReplicator() {
  stop();
  reader_.reset();
  writer_.reset();  // disposes nothing: the other sites see the writer go and ramp our items out
  participant_.reset();
}

void ItemReplicator::start() {
  if (thread_.joinable()) return;
  stopping_.store(false);
  thread_ = std::thread([this] {
    while (!stopping_.load(std::memory_order_relaxed)) {
      poll();
      std::this_thread::sleep_for(options_.period);
    }
  });
}

void ItemReplicator::stop() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
}

void ItemReplicator::poll() { poll(std::chrono::steady_clock::now()); }

void ItemReplicator::poll(std::chrono::steady_clock::time_point now) {
  publish_changes();
  apply_arrivals(now);
  limiter_.flush(now, log_lines_);
  for (const std::string& line : log_lines_) log(line);
  log_lines_.clear();
}

void ItemReplicator::log_limited(const std::string& key, const std::string& line,
                                 std::chrono::steady_clock::time_point now) {
  limiter_.admit(key, line, now, log_lines_);
  for (const std::string& line_now : log_lines_) log(line_now);
  log_lines_.clear();
}

void ItemReplicator::log(const std::string& line) const {
  if (options_.log) options_.log(line);
}

void ItemReplicator::publish_changes() {
  const std::uint64_t generation = scene_.generation();
  if (generation == seen_generation_) return;
  seen_generation_ = generation;
  std::set<std::uint64_t> live;
  for (const LocalSharedItem& item : scene_.shared_items()) {
    live.insert(item.id);
    Published& published = published_items_[item.id];
    if (published.version_key == item.version_key) continue;
    if (!writer_) {
      published.version_key = item.version_key;  // said once per version
      log("federation: item " + std::to_string(item.id) + " not shared: " + refusal_);
      continue;
    }
    SharedItemState state{options_.site, item.id, published.version + 1, item.kind, scene_.describe(item.id)};
    if (state.spec.empty()) continue;  // gone since shared_items(); the next round removes it
    if (writer_->put(state)) {
      published.version_key = item.version_key;
      published.version = state.version;
      published_.fetch_add(1, std::memory_order_relaxed);
    } else {
      log("federation: item " + std::to_string(item.id) + " not shared: " + writer_->error());
    }
  }
  for (auto it = published_items_.begin(); it != published_items_.end();) {
    if (live.count(it->first) != 0) {
      ++it;
      continue;
    }
    if (it->second.version > 0 && writer_ && !writer_->remove(options_.site, it->first)) {
      log("federation: item " + std::to_string(it->first) + " removal not sent: " + writer_->error());
    }
    it = published_items_.erase(it);
  }
}

void ItemReplicator::apply_arrivals(std::chrono::steady_clock::time_point now) {
  events_.clear();
  reader_->take(events_);
  for (const SharedItemEvent& event : events_) {
    const std::string which = "site " + event.state.site + " item " + std::to_string(event.state.item);
    if (event.what != SharedItemEvent::What::kLost && event.writer_site != event.state.site) {
      // Another site (or a writer in no single partition) speaking for this one: refused, and
      // nothing of the named site's items changes.
      refused_.fetch_add(1, std::memory_order_relaxed);
      log_limited(event.state.site + "\nforged",
                  "federation: " + which + (event.what == SharedItemEvent::What::kPut ? " (version " + std::to_string(event.state.version) + ")" : std::string(" removal")) +
                      " refused: its writer speaks for " +
                      (event.writer_site.empty() ? std::string("no single site") : "site \"" + event.writer_site + "\"") +
                      " (a site publishes only under its own name)",
                  now);
      continue;
    }
    switch (event.what) {
      case SharedItemEvent::What::kPut: {
        const std::string error = scene_.put_remote(event.state);
        if (error.empty()) {
          applied_.fetch_add(1, std::memory_order_relaxed);
        } else {
          refused_.fetch_add(1, std::memory_order_relaxed);
          log_limited(event.state.site + "\nrefused",
                      "federation: " + which + " (version " + std::to_string(event.state.version) + ") refused: " + error,
                      now);
        }
        break;
      }
      case SharedItemEvent::What::kRemoved:
        scene_.remove_remote(event.state.site, event.state.item);
        break;
      case SharedItemEvent::What::kLost:
        log_limited(event.state.site + "\nlost", "federation: " + which + " ramps out: its site is no longer heard",
                    now);
        scene_.remove_remote(event.state.site, event.state.item);
        break;
    }
  }
}

}  // namespace haptic::federation
