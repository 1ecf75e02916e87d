#include "net/event_hub.hpp"

#include <algorithm>

namespace haptic::net {

std::optional<v1::Event> EventHub::Watcher::next(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  ready_.wait_for(lock, timeout, [this] { return !queue_.empty() || closed_; });
  if (queue_.empty()) return std::nullopt;
  v1::Event event = std::move(queue_.front());
  queue_.pop_front();
  return event;
}

bool EventHub::Watcher::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

std::shared_ptr<EventHub::Watcher> EventHub::watch() {
  auto watcher = std::make_shared<Watcher>();
  std::lock_guard lock(mutex_);
  watchers_.push_back(watcher);
  return watcher;
}

void EventHub::unwatch(const std::shared_ptr<Watcher>& watcher) {
  std::lock_guard lock(mutex_);
  std::erase(watchers_, watcher);
}

void EventHub::publish(const v1::Event& event) {
  std::lock_guard lock(mutex_);
  for (const auto& watcher : watchers_) {
    {
      std::lock_guard watcher_lock(watcher->mutex_);
      if (watcher->queue_.size() >= kQueueLimit) {
        watcher->queue_.pop_front();
        ++watcher->lost_;
      }
      watcher->queue_.push_back(event);
    }
    watcher->ready_.notify_one();
  }
}

void EventHub::close() {
  std::lock_guard lock(mutex_);
  for (const auto& watcher : watchers_) {
    {
      std::lock_guard watcher_lock(watcher->mutex_);
      watcher->closed_ = true;
    }
    watcher->ready_.notify_all();
  }
  watchers_.clear();
}

}  // namespace haptic::net
