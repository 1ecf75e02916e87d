#include "clock_sync.hpp"

#include <algorithm>

namespace haptic::detail {

std::int64_t ClockSync::add(std::int64_t server_ns, std::int64_t local_ns) {
  const std::int64_t server_minus_local = server_ns - local_ns;
  if (server_minus_local > window_best_) {
    window_best_ = server_minus_local;
    window_best_local_ = local_ns;
  }
  estimate_ = std::max(estimate_, window_best_);
  if (++window_count_ == kWindow) {
    estimate_ = window_best_;
    points_[next_point_] = {window_best_local_, window_best_};
    next_point_ = (next_point_ + 1) % kPoints;
    point_count_ = std::min(point_count_ + 1, kPoints);
    if (point_count_ >= 2) {
      // Least squares of offset against local time, about the means (the times are ~1e18 ns:
      // centred first so the products do not lose the slope's digits).
      double mean_t = 0.0, mean_o = 0.0;
      for (std::size_t i = 0; i < point_count_; ++i) {
        mean_t += static_cast<double>(points_[i].local_ns - points_[0].local_ns);
        mean_o += static_cast<double>(points_[i].offset_ns - points_[0].offset_ns);
      }
      mean_t /= static_cast<double>(point_count_);
      mean_o /= static_cast<double>(point_count_);
      double stt = 0.0, sto = 0.0;
      for (std::size_t i = 0; i < point_count_; ++i) {
        const double t = static_cast<double>(points_[i].local_ns - points_[0].local_ns) - mean_t;
        const double o = static_cast<double>(points_[i].offset_ns - points_[0].offset_ns) - mean_o;
        stt += t * t;
        sto += t * o;
      }
      if (stt > 0.0) drift_ = sto / stt;
    }
    window_best_ = INT64_MIN;
    window_count_ = 0;
  }
  return std::max<std::int64_t>(0, estimate_ - server_minus_local);
}

std::optional<std::int64_t> ClockSync::offset_ns() const {
  if (estimate_ == INT64_MIN) return std::nullopt;
  return estimate_;
}

std::optional<double> ClockSync::drift() const { return drift_; }

std::optional<std::int64_t> ClockSync::server_ns_at(std::int64_t local_ns) const {
  if (estimate_ == INT64_MIN) return std::nullopt;
  if (!drift_ || point_count_ == 0) return local_ns + estimate_;
  const Point& newest = points_[(next_point_ + kPoints - 1) % kPoints];
  return local_ns + newest.offset_ns +
         static_cast<std::int64_t>(*drift_ * static_cast<double>(local_ns - newest.local_ns));
}

}  // namespace haptic::detail
