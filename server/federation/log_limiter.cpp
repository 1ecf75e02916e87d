#include "federation/log_limiter.hpp"

#include <cstdio>

namespace haptic::federation {

namespace {

std::string seconds(std::chrono::steady_clock::duration d) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", std::chrono::duration<double>(d).count());
  return text;
}

}  // namespace

bool LogLimiter::close(Window& window, Clock::time_point now, std::vector<std::string>& out) const {
  if (window.suppressed == 0) return false;
  // The last line stands for itself; the others are the count.
  std::string summary = window.last;
  if (window.suppressed > 1) {
    summary += " (and " + std::to_string(window.suppressed - 1) + " more in " + seconds(window_) + " s)";
  }
  out.push_back(std::move(summary));
  window.opened = now;
  window.suppressed = 0;
  window.last.clear();
  return true;
}

void LogLimiter::admit(const std::string& key, const std::string& line, Clock::time_point now,
                       std::vector<std::string>& out) {
  const auto it = windows_.find(key);
  if (it == windows_.end()) {
    windows_.emplace(key, Window{now, 0, {}});
    out.push_back(line);
    return;
  }
  Window& window = it->second;
  if (now - window.opened >= window_ && !close(window, now, out)) {
    window.opened = now;  // quiet for a whole window: written at once
    out.push_back(line);
    return;
  }
  ++window.suppressed;
  window.last = line;
}

void LogLimiter::flush(Clock::time_point now, std::vector<std::string>& out) {
  for (auto it = windows_.begin(); it != windows_.end();) {
    if (now - it->second.opened < window_ || close(it->second, now, out)) {
      ++it;
    } else {
      it = windows_.erase(it);
    }
  }
}

std::uint64_t LogLimiter::pending() const {
  std::uint64_t total = 0;
  for (const auto& [key, window] : windows_) total += window.suppressed;
  return total;
}

}  // namespace haptic::federation
