#include "federation/dds_log.hpp"

#include <mutex>
#include <vector>

#include <dds/dds.h>

#include "federation/log_limiter.hpp"

namespace haptic::federation {

namespace {

struct Route {
  std::mutex mutex;
  std::function<void(DdsLogLevel, const std::string&)> write;
  LogLimiter limiter;
  std::vector<std::string> lines;  // scratch
};

Route& route() {
  static Route* const instance = new Route;  // outlives every Cyclone thread that may call it
  return *instance;
}

DdsLogLevel level_of(std::uint32_t priority) {
  if ((priority & (DDS_LC_FATAL | DDS_LC_ERROR)) != 0) return DdsLogLevel::kError;
  if ((priority & DDS_LC_WARNING) != 0) return DdsLogLevel::kWarning;
  return DdsLogLevel::kInfo;
}

/// The level's mark at the head of a key, so that the summary is written at the same level.
char mark(DdsLogLevel level) { return level == DdsLogLevel::kError ? 'E' : level == DdsLogLevel::kWarning ? 'W' : 'I'; }

DdsLogLevel unmark(char c) { return c == 'E' ? DdsLogLevel::kError : c == 'W' ? DdsLogLevel::kWarning : DdsLogLevel::kInfo; }

/// The lines in `route.lines`, each with its level's mark first, written and cleared.
void write_lines(Route& r) {
  for (const std::string& line : r.lines) {
    if (!line.empty() && r.write) r.write(unmark(line.front()), line.substr(1));
  }
  r.lines.clear();
}

void sink(void*, const dds_log_data_t* data) {
  // The message without Cyclone's header (time, domain, thread), which comes before it: spdlog
  // has its own time.
  std::string text(data->message, data->size);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const DdsLogLevel level = level_of(data->priority);
  const std::string line = mark(level) + ("dds: " + text);
  Route& r = route();
  std::lock_guard lock(r.mutex);
  const auto now = std::chrono::steady_clock::now();
  r.limiter.flush(now, r.lines);
  r.limiter.admit(line, line, now, r.lines);
  write_lines(r);
}

}  // namespace

void route_dds_log(std::function<void(DdsLogLevel, const std::string&)> write) {
  Route& r = route();
  const bool on = static_cast<bool>(write);
  {
    std::lock_guard lock(r.mutex);
    r.write = std::move(write);
  }
  // Synchronous: once it returns, no Cyclone thread is in the old sink.
  dds_set_log_sink(on ? &sink : nullptr, nullptr);
}

void flush_dds_log(std::chrono::steady_clock::time_point now) {
  Route& r = route();
  std::lock_guard lock(r.mutex);
  r.limiter.flush(now, r.lines);
  write_lines(r);
}

}  // namespace haptic::federation
