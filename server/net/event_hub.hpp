#pragma once
// Fan-out of server events to WatchEvents streams. Each watcher has a bounded queue; a watcher
// that does not keep up loses its oldest events (counted) rather than slowing anyone else.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "haptic/v1/service.pb.h"

namespace haptic::net {

class EventHub {
 public:
  class Watcher {
   public:
    /// Waits up to `timeout` for the next event; nullopt on timeout or when the hub closed.
    std::optional<v1::Event> next(std::chrono::milliseconds timeout);
    bool closed() const;

   private:
    friend class EventHub;
    mutable std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<v1::Event> queue_;
    bool closed_ = false;
    std::uint64_t lost_ = 0;
  };

  static constexpr std::size_t kQueueLimit = 1024;

  std::shared_ptr<Watcher> watch();
  void unwatch(const std::shared_ptr<Watcher>& watcher);
  void publish(const v1::Event& event);
  /// Ends every watch (shutdown).
  void close();

 private:
  std::mutex mutex_;
  std::vector<std::shared_ptr<Watcher>> watchers_;
};

}  // namespace haptic::net
