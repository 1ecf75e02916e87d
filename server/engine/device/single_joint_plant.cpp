#include "engine/device/single_joint_plant.hpp"
#include "engine/core/parameter_checks.hpp"

#include <cassert>
#include <cmath>
#include <sstream>

namespace haptic::engine {
namespace {

SingleJointParams with_row(double J, double B, double f) {
  SingleJointParams p;
  p.inertia = J;
  p.damping = B;
  p.coulomb = f;
  return p;
}

}  // namespace

std::string SingleJointParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!positive(inertia)) return bad_parameter("inertia", "must be finite and > 0", inertia);
  if (!non_negative(damping)) return bad_parameter("damping", "must be finite and >= 0", damping);
  if (!non_negative(coulomb)) return bad_parameter("coulomb", "must be finite and >= 0", coulomb);
  if (!positive(stick_velocity)) {
    return bad_parameter("stick_velocity", "must be finite and > 0", stick_velocity);
  }
  if (!positive(torque_limit)) return bad_parameter("torque_limit", "must be finite and > 0", torque_limit);
  return {};
}

// Table 5.4 (L2617–2621).
SingleJointParams SingleJointParams::axial() { return with_row(0.204, 0.012, 0.088); }
SingleJointParams SingleJointParams::vertical() { return with_row(0.026, 0.009, 0.082); }
SingleJointParams SingleJointParams::horizontal() { return with_row(0.733, 0.045, 0.125); }

SingleJointPlant::SingleJointPlant(const SingleJointParams& params, const SingleJointState& initial,
                                   const IntegrationSettings& integration)
    : params_(params), state_(initial), integration_(integration) {
  assert(params.validate().empty());
}

}  // namespace haptic::engine
