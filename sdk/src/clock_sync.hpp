#pragma once
// The server's clock seen from the client, NTP-style over the state stream: every State carries
// its server time stamp, and the least-delayed samples bound the offset (server − local) from
// below by the smallest one-way delay. Per window of samples the largest server − receipt is the
// offset; the windows' least-delayed points, a few seconds apart, give the drift by least squares.

#include <array>
#include <cstdint>
#include <optional>

namespace haptic::detail {

class ClockSync {
 public:
  /// The offset estimate restarts its window every this many samples, so it follows drift.
  static constexpr std::uint32_t kWindow = 2000;
  /// Windows' least-delayed points the drift is fitted to.
  static constexpr std::size_t kPoints = 16;

  /// One sample: its server stamp and its local receipt time (ns, steady clock). Returns how much
  /// longer than the quickest recent sample it took (ns, >= 0): time spent queued anywhere.
  std::int64_t add(std::int64_t server_ns, std::int64_t local_ns);

  /// Server time − local time (ns), biased low by the smallest one-way delay; none before a sample.
  std::optional<std::int64_t> offset_ns() const;
  /// How much faster the server's clock runs than the local one (dimensionless: 5e-5 is
  /// 50 ppm); none before two windows have closed.
  std::optional<double> drift() const;
  /// The server's time (ns) at local time `local_ns`: the newest window's offset carried forward
  /// with the drift, or the offset alone while no drift is known; none before a sample.
  std::optional<std::int64_t> server_ns_at(std::int64_t local_ns) const;

 private:
  struct Point {
    std::int64_t local_ns;   // receipt time of the window's least-delayed sample
    std::int64_t offset_ns;  // its server − local
  };

  std::int64_t window_best_ = INT64_MIN;  // the current window's largest server − local
  std::int64_t window_best_local_ = 0;
  std::int64_t estimate_ = INT64_MIN;     // the offset in use
  std::uint32_t window_count_ = 0;
  std::array<Point, kPoints> points_{};
  std::size_t point_count_ = 0;           // points held, up to kPoints
  std::size_t next_point_ = 0;            // ring position of the next point
  std::optional<double> drift_;
};

}  // namespace haptic::detail
