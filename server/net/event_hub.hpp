#pragma once
// Fan-out of server events to WatchEvents streams. Each watcher has a bounded queue; a watcher
// that does not keep up loses its oldest events (counted) rather than slowing anyone else.
// Watches are bounded per session and server-wide (every one holds a control-plane thread for its
// lifetime), and a session's watches end with it.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "haptic/v1/service.pb.h"

namespace haptic::net {

struct WatchLimits {
  std::size_t per_session = 4;  // WatchEvents streams one session may hold at once
  std::size_t total = 32;       // ... and all sessions together
  std::size_t per_peer = 0;     // ... and the sessions of one host together; 0: no share
  std::size_t per_token = 0;    // ... and the sessions of one token, from any hosts; 0: no share
};

class EventHub {
 public:
  class Watcher {
   public:
    /// Waits up to `timeout` for the next event; nullopt on timeout or when the watch has ended
    /// and every event queued before the end has been taken.
    std::optional<v1::Event> next(std::chrono::milliseconds timeout);
    /// The watch has ended (its session ended, or the hub closed) and its queue is drained.
    bool finished() const;

   private:
    friend class EventHub;
    std::uint64_t session_id_ = 0;
    std::string host_;   // the host its session was opened from
    std::string token_;  // the name of the token its session was opened with ("" without)
    mutable std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<v1::Event> queue_;
    bool closed_ = false;
    std::uint64_t lost_ = 0;
  };

  static constexpr std::size_t kQueueLimit = 1024;

  explicit EventHub(WatchLimits limits = {}) : limits_(limits) {}

  /// A new watch for `session_id`, opened from `host` with the token named `token`; nullptr,
  /// with `refusal` naming the limit, when the session, the host, the token or the server already
  /// holds its most.
  std::shared_ptr<Watcher> watch(std::uint64_t session_id, std::string& refusal,
                                 const std::string& host = {}, const std::string& token = {});
  void unwatch(const std::shared_ptr<Watcher>& watcher);
  void publish(const v1::Event& event);
  /// Ends the session's watches once they have delivered what is queued (the session's own
  /// closing event among it).
  void end_session(std::uint64_t session_id);
  /// Ends every watch (shutdown).
  void close();
  /// Watches open now.
  std::size_t size() const;

 private:
  static void end(Watcher& watcher);

  WatchLimits limits_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Watcher>> watchers_;
  bool closed_ = false;
};

}  // namespace haptic::net
