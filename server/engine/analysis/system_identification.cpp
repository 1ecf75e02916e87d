#include "engine/analysis/system_identification.hpp"

#include "engine/analysis/moving_stretch_fit.hpp"

#include <algorithm>
#include <array>
#include <deque>
#include <functional>
#include <cmath>
#include <numbers>
#include <limits>
#include <set>

namespace haptic::engine {
namespace {

using identification::Parameters;
using identification::least_squares;
using identification::minimise;

constexpr double kPi = std::numbers::pi;

std::size_t ramp_ticks(const MultisineParams& p) {
  return static_cast<std::size_t>(std::llround(p.ramp_s / p.sample_period_s));
}

/// Student's t at 0.975 for `dof` degrees of freedom (tables; 1.96 beyond 120).
double t_975(std::size_t dof) {
  static constexpr std::array<double, 30> kTable = {
      12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
      2.120,  2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof == 0) return std::numeric_limits<double>::infinity();
  if (dof <= kTable.size()) return kTable[dof - 1];
  if (dof <= 60) return 2.000;
  if (dof <= 120) return 1.980;
  return 1.960;
}

/// The averaged period's spectrum at the excited harmonics, and what (1) needs from it.
struct Spectrum {
  std::vector<std::complex<double>> x, f, sign;  // X_k, F_k, S_k (of sgn ẋ)
  std::vector<double> omega;                     // ω_k. Unit: rad/s.
  std::vector<double> hold;                      // the hold's magnitude at ω_k, sin(ωT/2)/(ωT/2)
  double force_mean = 0.0;                       // F's mean. Unit: N.
  double sign_mean = 0.0;                        // sgn ẋ's mean
  double drift_velocity = 0.0;                   // ẋ's mean. Unit: m/s.
};


/// cos and sin of 2π j / N for j < N: every harmonic's phase at sample n is (k n mod N).
struct PhaseTable {
  explicit PhaseTable(std::size_t n) : cos(n), sin(n) {
    for (std::size_t j = 0; j < n; ++j) {
      const double angle = 2.0 * kPi * static_cast<double>(j) / static_cast<double>(n);
      cos[j] = std::cos(angle);
      sin[j] = std::sin(angle);
    }
  }
  std::vector<double> cos, sin;
};

/// The DFT (2/N scaled) of one period's samples at harmonic k.
std::complex<double> harmonic(std::span<const double> period, std::size_t k, const PhaseTable& table) {
  const std::size_t n_total = period.size();
  double re = 0.0, im = 0.0;
  std::size_t j = 0;
  for (std::size_t n = 0; n < n_total; ++n) {
    re += period[n] * table.cos[j];
    im -= period[n] * table.sin[j];
    j += k;
    while (j >= n_total) j -= n_total;
  }
  const double scale = 2.0 / static_cast<double>(n_total);
  return {re * scale, im * scale};
}

class Fitter {
 public:
  Fitter(const Multisine& excitation, std::span<const double> force, std::span<const double> position)
      : n_(excitation.params.samples_per_period), period_(excitation.params.sample_period_s) {
    const std::size_t begin = excitation.fit_begin_tick();
    periods_ = excitation.params.periods;
    force_.assign(force.begin() + static_cast<std::ptrdiff_t>(begin),
                  force.begin() + static_cast<std::ptrdiff_t>(begin + periods_ * n_));
    position_.assign(position.begin() + static_cast<std::ptrdiff_t>(begin),
                     position.begin() + static_cast<std::ptrdiff_t>(begin + periods_ * n_));
    detrend();
    f0_ = 1.0 / (static_cast<double>(n_) * excitation.params.sample_period_s);
    harmonics_ = excitation.harmonics;
    for (const std::size_t k : harmonics_) omega_.push_back(2.0 * kPi * static_cast<double>(k) * f0_);
    // The velocity whose sign is the friction's holds what friction puts at other harmonics too:
    // every harmonic up to twice the highest excited (a quarter of the samples at most).
    velocity_harmonics_ = std::min(n_ / 4, 2 * harmonics_.back());
  }

  std::size_t periods() const { return periods_; }
  const std::vector<double>& raw_window() const { return raw_; }

  /// The noise's rms: what consecutive periods disagree on, d[n] = x_p[n] − x_(p−1)[n], with its
  /// smooth part taken out by the second difference in time. On white noise of rms σ, d has
  /// variance 2σ² and d[n+1] − 2d[n] + d[n−1] six times that, 12σ²; a transient still decaying
  /// (a light device's, m/b of a second) or a drift changes d slowly and leaves it almost nothing,
  /// where the plain disagreement between periods would count it as noise. Unit: m.
  double noise_rms() const {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t p = 1; p < periods_; ++p) {
      const auto d = [&](std::size_t n) { return position_[p * n_ + n] - position_[(p - 1) * n_ + n]; };
      for (std::size_t n = 1; n + 1 < n_; ++n) {
        const double second = d(n + 1) - 2.0 * d(n) + d(n - 1);
        sum += second * second;
        ++count;
      }
    }
    return count > 0 ? std::sqrt(sum / (12.0 * static_cast<double>(count))) : 0.0;
  }

  /// The fit of (1) to the average of every period but `left_out` (none: all of them), with a
  /// lag τ_a searched over [0, max_lag] when max_lag > 0 (else none).
  std::optional<Parameters> fit(std::optional<std::size_t> left_out, double max_delay, double max_lag,
                                std::string& why) const {
    const Spectrum spectrum = spectrum_of(left_out);
    double motion = 0.0;
    for (const auto& x : spectrum.x) motion += std::norm(x);
    const auto [lowest, highest] = std::minmax_element(raw_.begin(), raw_.end());
    if (!(*highest > *lowest) || !(motion > 1e-24)) {
      why = "the axis did not move at the excited frequencies";
      return std::nullopt;
    }
    double lag = 0.0;
    if (max_lag > 0.0) {
      // τ_a: a grid over [0, max_lag], each point with its best τ (a lag and a delay trade
      // against each other at low ωτ, so each lag is given its own), then the same search.
      const auto at_lag = [&](double l) { return best_delay(spectrum, l, max_delay, 100); };
      lag = minimise(at_lag, 0.0, max_lag, 40, 40).lag;
    }
    Parameters result = best_delay(spectrum, lag, max_delay, 400);
    if (!std::isfinite(result.mass) || !std::isfinite(result.damping)) {
      why = "the fit is singular (an excitation too narrow to tell mass from damping?)";
      return std::nullopt;
    }
    return result;
  }

  /// τ in [0, max_delay] for a given lag.
  static Parameters best_delay(const Spectrum& spectrum, double lag, double max_delay, std::size_t grid) {
    return minimise([&](double tau) { return solve(spectrum, tau, lag); }, 0.0, max_delay, grid, 60);
  }

  /// The measured X/F at each harmonic of the full average.
  std::vector<std::complex<double>> measured_response() const {
    const Spectrum s = spectrum_of(std::nullopt);
    std::vector<std::complex<double>> out;
    for (std::size_t i = 0; i < s.x.size(); ++i) out.push_back(s.x[i] / s.f[i]);
    return out;
  }
  const std::vector<double>& omega() const { return omega_; }

 private:
  /// Takes a straight line through the periods' mean positions out of the positions: a drift
  /// (a load friction does not hold, a slow initial velocity) is not periodic, and would leak into
  /// every harmonic of the average. Its velocity is kept: it moves the friction's reversals and
  /// costs damping force in the mean. The raw window is kept for the quantization.
  void detrend() {
    raw_ = position_;
    std::vector<double> means(periods_, 0.0);
    for (std::size_t p = 0; p < periods_; ++p) {
      for (std::size_t n = 0; n < n_; ++n) means[p] += position_[p * n_ + n];
      means[p] /= static_cast<double>(n_);
    }
    double mean_p = 0.0, mean_m = 0.0;
    for (std::size_t p = 0; p < periods_; ++p) {
      mean_p += static_cast<double>(p);
      mean_m += means[p];
    }
    mean_p /= static_cast<double>(periods_);
    mean_m /= static_cast<double>(periods_);
    double spp = 0.0, spm = 0.0;
    for (std::size_t p = 0; p < periods_; ++p) {
      spp += (static_cast<double>(p) - mean_p) * (static_cast<double>(p) - mean_p);
      spm += (static_cast<double>(p) - mean_p) * (means[p] - mean_m);
    }
    const double slope = spp > 0.0 ? spm / spp : 0.0;  // per period
    drift_velocity_ = slope / (static_cast<double>(n_) * period_);
    for (std::size_t j = 0; j < position_.size(); ++j) {
      // The line through the periods' means, which sit at their periods' middles.
      const double periods_in = static_cast<double>(j) / static_cast<double>(n_) -
                                (static_cast<double>(n_) - 1.0) / (2.0 * static_cast<double>(n_));
      position_[j] -= slope * (periods_in - mean_p);
    }
  }

  std::vector<double> average(const std::vector<double>& values, std::optional<std::size_t> left_out) const {
    std::vector<double> mean(n_, 0.0);
    std::size_t count = 0;
    for (std::size_t p = 0; p < periods_; ++p) {
      if (left_out && *left_out == p) continue;
      ++count;
      for (std::size_t n = 0; n < n_; ++n) mean[n] += values[p * n_ + n];
    }
    for (double& v : mean) v /= static_cast<double>(count);
    return mean;
  }

  Spectrum spectrum_of(std::optional<std::size_t> left_out) const {
    const std::vector<double> x = average(position_, left_out);
    const std::vector<double> f = average(force_, left_out);
    Spectrum s;
    s.omega = omega_;
    for (const double w : omega_) s.hold.push_back(std::sin(w * period_ / 2.0) / (w * period_ / 2.0));
    for (const std::size_t k : harmonics_) {
      s.x.push_back(harmonic(x, k, table_));
      s.f.push_back(harmonic(f, k, table_));
    }
    for (const double v : f) s.force_mean += v;
    s.force_mean /= static_cast<double>(n_);
    // The velocity, Σ Re(jω X e^{jωt}) over the harmonics up to velocity_harmonics_, and the
    // drift's: their sum's sign is the friction's direction.
    s.drift_velocity = drift_velocity_;
    std::vector<double> velocity(n_, drift_velocity_);
    for (std::size_t k = 1; k <= velocity_harmonics_; ++k) {
      const std::complex<double> xk = harmonic(x, k, table_);
      const double w = 2.0 * kPi * static_cast<double>(k) * f0_;
      std::size_t j = 0;
      for (std::size_t n = 0; n < n_; ++n) {
        // Re(jω X (cos + j sin)) = −ω (Re X sin + Im X cos)
        velocity[n] -= w * (xk.real() * table_.sin[j] + xk.imag() * table_.cos[j]);
        j += k;
        while (j >= n_) j -= n_;
      }
    }
    std::vector<double> sign(n_, 0.0);
    for (std::size_t n = 0; n < n_; ++n) {
      sign[n] = velocity[n] > 0.0 ? 1.0 : (velocity[n] < 0.0 ? -1.0 : 0.0);
      s.sign_mean += sign[n];
    }
    s.sign_mean /= static_cast<double>(n_);
    for (const std::size_t k : harmonics_) s.sign.push_back(harmonic(sign, k, table_));
    return s;
  }

  /// (m, b, c) by least squares at the harmonics for a given τ and τ_a: H(ω) F_k e^{−jωτ} /
  /// (1 + jωτ_a) = (−mω² + jbω) X_k + c S_k, real and imaginary parts stacked; f0 from the means.
  /// H(ω) = sin(ωT/2) / (ωT/2) is the magnitude of the loop's zero-order hold (its phase, ωT/2,
  /// is part of τ).
  static Parameters solve(const Spectrum& s, double tau, double lag) {
    double ata[3][3] = {}, atb[3] = {};
    double force_power = 0.0;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const double w = s.omega[i];
      const std::complex<double> target = s.f[i] * std::polar(s.hold[i], -w * tau) / std::complex<double>(1.0, w * lag);
      const std::array<std::complex<double>, 3> column = {-w * w * s.x[i], std::complex<double>(0.0, w) * s.x[i],
                                                          s.sign[i]};
      for (int part = 0; part < 2; ++part) {
        const std::array<double, 3> row = {part == 0 ? column[0].real() : column[0].imag(),
                                           part == 0 ? column[1].real() : column[1].imag(),
                                           part == 0 ? column[2].real() : column[2].imag()};
        const double y = part == 0 ? target.real() : target.imag();
        for (int r = 0; r < 3; ++r) {
          atb[r] += row[static_cast<std::size_t>(r)] * y;
          for (int c = 0; c < 3; ++c) ata[r][c] += row[static_cast<std::size_t>(r)] * row[static_cast<std::size_t>(c)];
        }
      }
      force_power += std::norm(s.f[i]);
    }
    // A friction column of zeros (no reversal seen) is left out: c = 0.
    std::array<bool, 3> used{};
    std::array<double, 3> solution = least_squares(ata, atb, used);
    if (!used[0] || !used[1]) solution[0] = solution[1] = std::numeric_limits<double>::quiet_NaN();
    Parameters p;
    p.mass = solution[0];
    p.damping = solution[1];
    p.coulomb = solution[2];
    p.offset = s.force_mean - p.damping * s.drift_velocity - p.coulomb * s.sign_mean;
    p.delay = tau;
    p.lag = lag;
    p.force_power = force_power;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const double w = s.omega[i];
      const std::complex<double> model =
          std::complex<double>(-p.mass * w * w, p.damping * w) * s.x[i] + p.coulomb * s.sign[i];
      p.residual += std::norm(s.f[i] * std::polar(s.hold[i], -w * tau) / std::complex<double>(1.0, w * lag) - model);
    }
    return p;
  }

  std::size_t n_;
  double period_;
  double drift_velocity_ = 0.0;  // the trend's, along the axis. Unit: m/s.
  std::size_t periods_ = 0;
  std::vector<double> force_, position_, raw_;
  PhaseTable table_{n_};
  double f0_ = 0.0;  // the period's frequency. Unit: Hz.
  std::vector<std::size_t> harmonics_;
  std::size_t velocity_harmonics_ = 0;
  std::vector<double> omega_;
};

}  // namespace

double Multisine::duration_s() const {
  const std::size_t ticks = 2 * ramp_ticks(params) + (params.settle_periods + params.periods) * params.samples_per_period;
  return static_cast<double>(ticks) * params.sample_period_s;
}

std::size_t Multisine::fit_begin_tick() const {
  return ramp_ticks(params) + params.settle_periods * params.samples_per_period;
}

std::size_t Multisine::fit_ticks() const { return params.periods * params.samples_per_period; }

double Multisine::force_at_tick(std::size_t tick) const {
  const std::size_t ramp = ramp_ticks(params);
  const std::size_t steady_end = ramp + (params.settle_periods + params.periods) * params.samples_per_period;
  const std::size_t end = steady_end + ramp;
  if (tick >= end) return 0.0;
  double envelope = 1.0;
  if (tick < ramp) {
    envelope = 0.5 * (1.0 - std::cos(kPi * static_cast<double>(tick) / static_cast<double>(ramp)));
  } else if (tick >= steady_end) {
    envelope = 0.5 * (1.0 + std::cos(kPi * static_cast<double>(tick - steady_end) / static_cast<double>(ramp)));
  }
  return envelope * scale * period[tick % params.samples_per_period];
}

std::optional<Multisine> design_multisine(const MultisineParams& params, std::string& why) {
  if (!(params.sample_period_s > 0.0) || params.samples_per_period < 16 || !(params.amplitude_n > 0.0) ||
      !std::isfinite(params.amplitude_n) || params.max_harmonics < 3 || params.periods < 4 ||
      !(params.ramp_s >= 0.0) || !(params.f_min_hz > 0.0) || !(params.f_max_hz > params.f_min_hz)) {
    why = "multisine: sample_period_s > 0, samples_per_period >= 16, amplitude_n > 0, max_harmonics >= 3, "
          "periods >= 4, ramp_s >= 0 and 0 < f_min_hz < f_max_hz are needed";
    return std::nullopt;
  }
  const double f0 = 1.0 / (static_cast<double>(params.samples_per_period) * params.sample_period_s);
  const auto k_min = static_cast<std::size_t>(std::max(1.0, std::round(params.f_min_hz / f0)));
  const auto k_max = static_cast<std::size_t>(
      std::min(std::floor(params.f_max_hz / f0), static_cast<double>(params.samples_per_period / 4)));
  if (k_max < k_min + 2) {
    why = "multisine: between f_min_hz and f_max_hz (at most a quarter of the sample rate) fit fewer than three "
          "harmonics of 1/(N T) = " + std::to_string(f0) + " Hz: widen the band or lengthen the period";
    return std::nullopt;
  }
  std::set<std::size_t> chosen;
  const std::size_t wanted = params.max_harmonics;
  for (std::size_t i = 0; i < wanted; ++i) {
    const double r = wanted == 1 ? 0.0 : static_cast<double>(i) / static_cast<double>(wanted - 1);
    chosen.insert(static_cast<std::size_t>(
        std::llround(static_cast<double>(k_min) * std::pow(static_cast<double>(k_max) / static_cast<double>(k_min), r))));
  }
  Multisine m;
  m.params = params;
  m.harmonics.assign(chosen.begin(), chosen.end());
  const double count = static_cast<double>(m.harmonics.size());
  for (std::size_t i = 1; i <= m.harmonics.size(); ++i) {
    m.phases.push_back(-kPi * static_cast<double>(i) * static_cast<double>(i - 1) / count);  // Schroeder 1970
  }
  double peak = 0.0;
  const std::size_t n = params.samples_per_period;
  m.period.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    double sum = 0.0;
    for (std::size_t i = 0; i < m.harmonics.size(); ++i) {
      sum += std::cos(2.0 * kPi * static_cast<double>(m.harmonics[i] * t % n) / static_cast<double>(n) + m.phases[i]);
    }
    m.period[t] = sum;
    peak = std::max(peak, std::abs(sum));
  }
  m.scale = params.amplitude_n / peak;
  return m;
}

namespace {

/// The step of distinct, sorted `values` that lie on a lattice whose step changes slowly along
/// the axis (see lattice_step): the median of the steps between clusters, or none.
std::optional<double> slowly_varying_lattice_step(const std::vector<double>& sorted) {
  std::vector<double> gaps;
  for (std::size_t i = 1; i < sorted.size(); ++i) gaps.push_back(sorted[i] - sorted[i - 1]);
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  // The steps' scale: the gap a twentieth of the gaps exceed (at least one), so that a few
  // outliers or skipped counts do not set it. The walk starts from the first eight gaps of a
  // quarter of that or more: the median of those within 1.5 times the smallest (a skipped count
  // makes one gap two steps).
  std::vector<double> by_size = gaps;
  const std::size_t rank = std::min(gaps.size() - 1, std::max<std::size_t>(1, gaps.size() / 20));
  std::nth_element(by_size.begin(), by_size.begin() + static_cast<std::ptrdiff_t>(rank), by_size.end(),
                   std::greater<>());
  const double scale = by_size[rank];
  std::vector<double> first;
  for (std::size_t i = 0; i < gaps.size() && first.size() < 8; ++i) {
    if (gaps[i] >= 0.25 * scale) first.push_back(gaps[i]);
  }
  if (first.empty()) return std::nullopt;
  const double smallest = *std::min_element(first.begin(), first.end());
  std::erase_if(first, [&](double g) { return g > 1.5 * smallest; });
  // Along the axis, every gap is another joint's count inside a cluster (under a fiftieth of the
  // local step, the cluster narrower than a twentieth), or whole local steps, at most 20, within
  // a twentieth of a step; the local step is the median of the last eight single steps, so the
  // map's slope may change.
  std::deque<double> recent{median(first)};
  std::vector<double> steps;
  double local = recent.front(), cluster = 0.0;
  for (const double g : gaps) {
    if (g < 0.02 * local) {
      cluster += g;
      if (cluster > 0.05 * local) return std::nullopt;
      continue;
    }
    const double counts = std::round(g / local);
    if (counts < 1.0 || counts > 20.0 || std::abs(g / local - counts) > 0.05) return std::nullopt;
    steps.push_back(g / counts);
    recent.push_back(g / counts);
    if (recent.size() > 8) recent.pop_front();
    local = median(std::vector<double>(recent.begin(), recent.end()));
    cluster = 0.0;
  }
  if (steps.size() < 8) return std::nullopt;
  return median(steps);
}

}  // namespace

std::optional<double> lattice_step(std::span<const double> values) {
  std::vector<double> sorted(values.begin(), values.end());
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  if (sorted.size() < 3) return std::nullopt;
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < sorted.size(); ++i) step = std::min(step, sorted[i] - sorted[i - 1]);
  // Whole steps to a hundredth of one at most: a tolerance that grew to half a step with the
  // span took plain noise for a lattice of its smallest gap.
  bool uniform = step > 0.0 && (sorted.back() - sorted.front()) / step <= 1e7;
  for (std::size_t i = 0; uniform && i < sorted.size(); ++i) {
    const double r = (sorted[i] - sorted.front()) / step;
    uniform = std::abs(r - std::round(r)) <= 1e-9 * r + 1e-6;
  }
  return uniform ? std::optional<double>(step) : slowly_varying_lattice_step(sorted);
}

std::optional<AxisIdentification> identify_axis(const Multisine& excitation, std::span<const double> force,
                                                std::span<const double> position, std::string& why,
                                                double max_delay_s, double max_lag_s, FitMethod method) {
  const std::size_t needed = excitation.fit_begin_tick() + excitation.fit_ticks();
  if (force.size() < needed || position.size() < needed) {
    why = "identify: " + std::to_string(std::min(force.size(), position.size())) + " ticks recorded, the excitation's fit "
          "needs " + std::to_string(needed);
    return std::nullopt;
  }
  for (std::size_t i = 0; i < needed; ++i) {
    if (!std::isfinite(force[i]) || !std::isfinite(position[i])) {
      why = "identify: tick " + std::to_string(i) + " holds a value that is not finite";
      return std::nullopt;
    }
  }
  const double max_delay = max_delay_s >= 0.0 ? max_delay_s : 20.0 * excitation.params.sample_period_s;
  const Fitter fitter(excitation, force, position);
  if (!(max_lag_s >= 0.0) || !std::isfinite(max_lag_s)) {
    why = "identify: the lag's bound must be finite and >= 0 (0: no lag), got " + std::to_string(max_lag_s);
    return std::nullopt;
  }
  // In time, over where the axis moved: its still speed from the noise and the step the
  // harmonics' fitter measures.
  std::optional<identification::MovingStretchFit> in_time;
  if (method == FitMethod::kMovingStretches) {
    in_time.emplace(force, position, excitation.params.sample_period_s, excitation.fit_begin_tick(),
                    excitation.params.samples_per_period, excitation.params.periods, fitter.noise_rms(),
                    lattice_step(fitter.raw_window()));
  }
  const auto fit_without = [&](std::optional<std::size_t> left_out, std::string& reason,
                               const Parameters* near = nullptr) {
    return in_time ? in_time->fit(left_out, max_delay, max_lag_s, reason, near)
                   : fitter.fit(left_out, max_delay, max_lag_s, reason);
  };
  const auto all = fit_without(std::nullopt, why);
  if (!all) return std::nullopt;
  // The delete-one-period jackknife (Efron & Tibshirani 1993, §11.2): each parameter refitted
  // with one period left out; its spread, times (P − 1)/P, is the estimate's variance.
  const std::size_t p = fitter.periods();
  std::vector<Parameters> leave_one_out;
  for (std::size_t i = 0; i < p; ++i) {
    std::string ignored;
    const auto fit = fit_without(i, ignored, &*all);
    if (!fit) {
      why = "identify: the fit without period " + std::to_string(i) + " failed: " + ignored;
      return std::nullopt;
    }
    leave_one_out.push_back(*fit);
  }
  const auto estimate = [&](double Parameters::*field) {
    double mean = 0.0;
    for (const Parameters& q : leave_one_out) mean += q.*field;
    mean /= static_cast<double>(p);
    double sum = 0.0;
    for (const Parameters& q : leave_one_out) sum += (q.*field - mean) * (q.*field - mean);
    Estimate e;
    e.value = (*all).*field;
    e.standard_error = std::sqrt(sum * static_cast<double>(p - 1) / static_cast<double>(p));
    e.half_width_95 = t_975(p - 1) * e.standard_error;
    return e;
  };
  AxisIdentification out;
  out.mass = estimate(&Parameters::mass);
  out.damping = estimate(&Parameters::damping);
  out.coulomb = estimate(&Parameters::coulomb);
  out.offset = estimate(&Parameters::offset);
  out.delay = estimate(&Parameters::delay);
  out.lag = estimate(&Parameters::lag);
  out.coulomb_positive = out.coulomb.value + out.offset.value;
  out.coulomb_negative = out.coulomb.value - out.offset.value;
  out.noise_rms_m = fitter.noise_rms();
  out.quantization_m = lattice_step(fitter.raw_window());
  out.relative_residual = all->force_power > 0.0 ? std::sqrt(all->residual / all->force_power) : 0.0;
  out.periods = p;
  out.method = method;
  if (in_time) out.moving_fraction = in_time->moving_fraction();
  const std::vector<std::complex<double>> measured = fitter.measured_response();
  const double f0 = 1.0 / (static_cast<double>(excitation.params.samples_per_period) * excitation.params.sample_period_s);
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const double w = fitter.omega()[i];
    FrequencyPoint point;
    point.frequency_hz = static_cast<double>(excitation.harmonics[i]) * f0;
    point.measured = measured[i];
    const double half = w * excitation.params.sample_period_s / 2.0;
    point.model = std::polar(std::sin(half) / half, -w * all->delay) / std::complex<double>(1.0, w * all->lag) /
                  std::complex<double>(-all->mass * w * w, all->damping * w);
    out.response.push_back(point);
  }
  return out;
}

}  // namespace haptic::engine
