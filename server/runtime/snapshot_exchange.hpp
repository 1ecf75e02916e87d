#pragma once
// Hands immutable snapshots (the compiled scene) from the control plane to the loop.
//
// Publishing (off the loop) swaps an atomic pointer; the loop adopts the newest snapshot at the top
// of a tick and reports the generation it adopted. Snapshots older than that generation can no
// longer be in use, and are freed off the loop by the next publish() or reclaim(). The loop never
// allocates, frees or locks.

#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>

namespace haptic::runtime {

template <typename T>
class SnapshotExchange {
 public:
  explicit SnapshotExchange(std::unique_ptr<const T> initial) { publish(std::move(initial)); }

  /// Off the loop. Makes `snapshot` the one the loop adopts at its next tick.
  std::uint64_t publish(std::unique_ptr<const T> snapshot) {
    std::lock_guard lock(mutex_);
    auto node = std::make_unique<Node>(Node{++last_generation_, std::move(snapshot)});
    current_.store(node.get(), std::memory_order_release);
    retained_.push_back(std::move(node));
    reclaim_locked();
    return last_generation_;
  }

  /// Off the loop. Frees snapshots the loop can no longer use.
  void reclaim() {
    std::lock_guard lock(mutex_);
    reclaim_locked();
  }

  /// Number of snapshots still held (the current one and any the loop may still be using).
  std::size_t retained() const {
    std::lock_guard lock(mutex_);
    return retained_.size();
  }

  /// On the loop, at the top of a tick: the newest snapshot. Lock- and allocation-free.
  const T& adopt() {
    return adopt([](const T&, const T&) {});
  }

  /// As adopt(); when the snapshot changes, first calls carry(previous, next) — while the
  /// previous one is still guaranteed alive — so the loop can carry its own state across.
  template <typename Carry>
  const T& adopt(Carry&& carry) {
    const Node* node = current_.load(std::memory_order_acquire);
    if (node != adopted_) {
      if (adopted_ != nullptr) carry(*adopted_->value, *node->value);
      adopted_ = node;
      adopted_generation_.store(node->generation, std::memory_order_release);
    }
    return *node->value;
  }

  /// Off the loop: calls f(snapshot) with the snapshot the loop adopted last, kept alive for the
  /// call (reclaim() cannot free it meanwhile). Returns false, without calling f, before the loop
  /// has adopted any.
  template <typename F>
  bool with_adopted(F&& f) const {
    std::lock_guard lock(mutex_);
    const std::uint64_t in_use = adopted_generation_.load(std::memory_order_acquire);
    for (const auto& node : retained_) {
      if (node->generation == in_use) {
        f(*node->value);
        return true;
      }
    }
    return false;
  }

  /// Generation the loop adopted last.
  std::uint64_t adopted_generation() const {
    return adopted_generation_.load(std::memory_order_acquire);
  }

 private:
  struct Node {
    std::uint64_t generation;
    std::unique_ptr<const T> value;
  };

  void reclaim_locked() {
    const std::uint64_t in_use = adopted_generation_.load(std::memory_order_acquire);
    while (retained_.size() > 1 && retained_.front()->generation < in_use) retained_.pop_front();
  }

  mutable std::mutex mutex_;
  std::deque<std::unique_ptr<Node>> retained_;  // oldest first; guarded by mutex_
  std::uint64_t last_generation_ = 0;           // guarded by mutex_
  std::atomic<const Node*> current_{nullptr};
  std::atomic<std::uint64_t> adopted_generation_{0};
  const Node* adopted_ = nullptr;  // loop thread only
};

}  // namespace haptic::runtime
