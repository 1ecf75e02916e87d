#include "net/event_hub.hpp"

#include <algorithm>

#include "haptic/io/session_id.hpp"

namespace haptic::net {

std::optional<v1::Event> EventHub::Watcher::next(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  ready_.wait_for(lock, timeout, [this] { return !queue_.empty() || closed_; });
  if (queue_.empty()) return std::nullopt;
  v1::Event event = std::move(queue_.front());
  queue_.pop_front();
  return event;
}

bool EventHub::Watcher::finished() const {
  std::lock_guard lock(mutex_);
  return closed_ && queue_.empty();
}

std::shared_ptr<EventHub::Watcher> EventHub::watch(std::uint64_t session_id, std::string& refusal,
                                                   const std::string& host, const std::string& token) {
  std::lock_guard lock(mutex_);
  if (closed_) {
    refusal = "the server is shutting down";
    return nullptr;
  }
  const auto held = static_cast<std::size_t>(std::count_if(
      watchers_.begin(), watchers_.end(),
      [&](const std::shared_ptr<Watcher>& w) { return w->session_id_ == session_id; }));
  if (held >= limits_.per_session) {
    refusal = "session " + io::format_session_id(session_id) + " already holds " +
              std::to_string(held) + " event streams, the most one session may "
              "(max_event_streams_per_session = " + std::to_string(limits_.per_session) + ")";
    return nullptr;
  }
  if (watchers_.size() >= limits_.total) {
    refusal = "the server already serves " + std::to_string(watchers_.size()) +
              " event streams, its most (max_event_streams = " + std::to_string(limits_.total) + ")";
    return nullptr;
  }
  // The watches whose `field` (their host, their token) is `value`.
  const auto held_by = [&](std::string Watcher::*field, const std::string& value) {
    return static_cast<std::size_t>(std::count_if(watchers_.begin(), watchers_.end(),
                                                  [&](const std::shared_ptr<Watcher>& w) { return (*w).*field == value; }));
  };
  if (limits_.per_peer > 0 && !host.empty()) {
    const std::size_t from_host = held_by(&Watcher::host_, host);
    if (from_host >= limits_.per_peer) {
      refusal = "the sessions from " + host + " already hold " + std::to_string(from_host) +
                " event streams, the most one host may (max_event_streams_per_peer = " +
                std::to_string(limits_.per_peer) + ")";
      return nullptr;
    }
  }
  if (limits_.per_token > 0 && !token.empty()) {
    const std::size_t with_token = held_by(&Watcher::token_, token);
    if (with_token >= limits_.per_token) {
      refusal = "the sessions of token '" + token + "' already hold " + std::to_string(with_token) +
                " event streams, the most one token may from all hosts together "
                "(max_event_streams_per_token = " + std::to_string(limits_.per_token) + ")";
      return nullptr;
    }
  }
  auto watcher = std::make_shared<Watcher>();
  watcher->session_id_ = session_id;
  watcher->host_ = host;
  watcher->token_ = token;
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
      if (watcher->closed_) continue;
      if (watcher->queue_.size() >= kQueueLimit) {
        watcher->queue_.pop_front();
        ++watcher->lost_;
      }
      watcher->queue_.push_back(event);
    }
    watcher->ready_.notify_one();
  }
}

void EventHub::end(Watcher& watcher) {
  {
    std::lock_guard watcher_lock(watcher.mutex_);
    watcher.closed_ = true;
  }
  watcher.ready_.notify_all();
}

void EventHub::end_session(std::uint64_t session_id) {
  std::lock_guard lock(mutex_);
  for (const auto& watcher : watchers_) {
    if (watcher->session_id_ == session_id) end(*watcher);
  }
}

void EventHub::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  for (const auto& watcher : watchers_) end(*watcher);
}

std::size_t EventHub::size() const {
  std::lock_guard lock(mutex_);
  return watchers_.size();
}

}  // namespace haptic::net
