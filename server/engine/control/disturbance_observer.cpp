#include "engine/control/disturbance_observer.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <numbers>
#include <sstream>

namespace haptic::engine {
namespace {

/// g = B̄ / (1 − e^{−x}) = (M̄/T) · x / (1 − e^{−x}), x = B̄T/M̄, with its limit M̄/T at B̄ = 0.
double nominal_inverse_gain(const DisturbanceObserverParams& p) {
  const double x = p.nominal_damping * p.sample_period / p.nominal_mass;
  const double factor = x > 0.0 ? x / -std::expm1(-x) : 1.0;
  return p.nominal_mass / p.sample_period * factor;
}

}  // namespace

std::string DisturbanceObserverParams::validate() const {
  if (!(std::isfinite(nominal_mass) && nominal_mass > 0.0)) {
    return bad_parameter("nominal_mass", "must be finite and > 0", nominal_mass);
  }
  if (!(std::isfinite(nominal_damping) && nominal_damping >= 0.0)) {
    return bad_parameter("nominal_damping", "must be finite and >= 0", nominal_damping);
  }
  if (!(std::isfinite(sample_period) && sample_period > 0.0)) {
    return bad_parameter("sample_period", "must be finite and > 0", sample_period);
  }
  if (!(std::isfinite(cutoff) && cutoff > 0.0 && cutoff < std::numbers::pi / sample_period)) {
    return bad_parameter("cutoff", "must be finite and in (0, π / sample_period)", cutoff);
  }
  return {};
}

DisturbanceObserver::DisturbanceObserver(const DisturbanceObserverParams& params)
    : params_(params),
      phi_(std::exp(-params.nominal_damping * params.sample_period / params.nominal_mass)),
      g_(nominal_inverse_gain(params)),
      a_(std::exp(-params.sample_period * params.cutoff)),
      one_minus_a_(-std::expm1(-params.sample_period * params.cutoff)) {
  assert(params.validate().empty());
}

}  // namespace haptic::engine
