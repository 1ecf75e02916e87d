#pragma once
// Lines that could repeat many times a second (a peer's refused samples, Cyclone's failed DDS
// Security handshakes with a rogue host) written once and then counted (docs/federation.md, "What
// a site logs"): the first line of a key is written at once; the key's further lines within the
// window are counted, and when the window ends one line says how many there were
// ("<the last of them> (and 37 more in 10 s)"), which opens the next window. A key quiet for a
// whole window starts afresh.
//
// Off the loop; not thread-safe (each thread that logs keeps its own, or locks).

#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace haptic::federation {

class LogLimiter {
 public:
  using Clock = std::chrono::steady_clock;

  explicit LogLimiter(Clock::duration window = std::chrono::seconds(10)) : window_(window) {}

  /// Appends to `out` what to write at `now` for `line` under `key`: a summary of the key's ended
  /// window, if any, then `line` itself unless the key has written one within the window (then
  /// it is counted).
  void admit(const std::string& key, const std::string& line, Clock::time_point now, std::vector<std::string>& out);
  /// Appends the summary of every window ended by `now` that counted lines, and forgets keys
  /// quiet for a whole window.
  void flush(Clock::time_point now, std::vector<std::string>& out);
  /// Lines counted and not yet summarized (all keys).
  std::uint64_t pending() const;

 private:
  struct Window {
    Clock::time_point opened;  // when its line (or summary) was written
    std::uint64_t suppressed = 0;
    std::string last;  // the newest suppressed line
  };
  /// The summary of an ended window, which reopens it; false when it counted nothing.
  bool close(Window& window, Clock::time_point now, std::vector<std::string>& out) const;

  Clock::duration window_;
  std::map<std::string, Window> windows_;
};

}  // namespace haptic::federation
