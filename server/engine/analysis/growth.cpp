#include "engine/analysis/growth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace haptic::engine {

GrowthFit envelope_growth(std::span<const double> size, double sample_period_s, double from_s, double window_s,
                          double floor) {
  GrowthFit fit{-std::numeric_limits<double>::infinity()};
  if (!(sample_period_s > 0.0) || !(window_s > 0.0)) return fit;
  const auto first = static_cast<std::size_t>(std::max(0.0, std::ceil(from_s / sample_period_s)));
  const auto per_window = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(window_s / sample_period_s)));
  // Least squares of ln(envelope) on the window's middle time.
  double n = 0.0, st = 0.0, sy = 0.0, stt = 0.0, sty = 0.0;
  for (std::size_t start = first; start + per_window <= size.size(); start += per_window) {
    double envelope = 0.0;
    for (std::size_t k = start; k < start + per_window; ++k) {
      const double magnitude = std::abs(size[k]);
      if (!std::isfinite(magnitude)) return GrowthFit{std::numeric_limits<double>::infinity(), fit.windows, magnitude};
      envelope = std::max(envelope, magnitude);
    }
    fit.last_envelope = envelope;
    if (!(envelope > floor)) continue;
    const double t = (static_cast<double>(start) + 0.5 * static_cast<double>(per_window)) * sample_period_s;
    const double y = std::log(envelope);
    n += 1.0;
    st += t;
    sy += y;
    stt += t * t;
    sty += t * y;
    ++fit.windows;
  }
  if (fit.windows < 3) return fit;
  const double denominator = n * stt - st * st;
  if (!(denominator > 0.0)) return fit;
  fit.rate_per_s = (n * sty - st * sy) / denominator;
  return fit;
}

bool rings_up(const GrowthFit& run, const GrowthFit* reference) {
  const double baseline = reference != nullptr ? std::max(reference->rate_per_s, 0.0) : 0.0;
  return run.rate_per_s > baseline + kRingUpRate;
}

}  // namespace haptic::engine
