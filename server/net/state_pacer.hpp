#pragma once
// The state streams of clients without UDP (the HTTP face's WebSockets), paced by one thread for
// all of them: each stream sends its port's newest sample on a grid of its period counted from one
// epoch, so that streams at one rate wake the thread once together, not once each (8 streams at
// 250 Hz: 250 wake-ups a second instead of 2,000). Each message is one State datagram as the UDP
// sender encodes it, with the stream's own sequence. Reads the SampleRings as the UDP sender does;
// never the loop. The sink runs on the pacer's thread: it must not block (a WebSocket's send
// queues).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "runtime/sample_ring.hpp"

namespace haptic::net {

class StatePacer {
 public:
  /// Takes a datagram; false once the stream's client is gone (the stream then ends).
  using Sink = std::function<bool(const std::string& datagram)>;

  struct Stream {
    std::uint64_t session_id = 0;
    wire::Key key{};
    const runtime::SampleRing* ring = nullptr;
    std::chrono::nanoseconds period{};
    Sink sink;
  };

  StatePacer();
  ~StatePacer();
  StatePacer(const StatePacer&) = delete;
  StatePacer& operator=(const StatePacer&) = delete;

  /// Starts pacing `stream`; the id remove() takes.
  std::uint64_t add(Stream stream);
  /// Stops it; once this returns its sink is never called again.
  void remove(std::uint64_t id);
  /// Whether the stream still runs (false once its sink refused a datagram).
  bool running(std::uint64_t id) const;

 private:
  struct Paced {
    std::uint64_t id = 0;
    Stream stream;
    std::chrono::steady_clock::time_point next;
    std::uint64_t sent_tick = 0;
    std::uint64_t sequence = 0;
    bool ended = false;
  };
  void run();
  /// The first point of `period`'s grid (counted from epoch_) after `now`.
  std::chrono::steady_clock::time_point next_on_grid(std::chrono::nanoseconds period,
                                                     std::chrono::steady_clock::time_point now) const;

  const std::chrono::steady_clock::time_point epoch_ = std::chrono::steady_clock::now();
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Paced> streams_;
  std::uint64_t next_id_ = 1;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace haptic::net
