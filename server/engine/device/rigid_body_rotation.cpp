#include "engine/device/rigid_body_rotation.hpp"

#include <string>

#include "engine/core/parameter_checks.hpp"

namespace haptic::engine {

std::string validate_rotation(const RotationParams& params) {
  if (!is_positive(params.inertia)) {
    return bad_parameter("inertia", "must be finite and > 0", params.inertia);
  }
  if (!is_non_negative(params.damping)) {
    return bad_parameter("damping", "must be finite and >= 0", params.damping);
  }
  if (params.substeps < 1 || params.substeps > 1000) {
    return bad_parameter("substeps", "must be 1 to 1000", static_cast<double>(params.substeps));
  }
  return {};
}

}  // namespace haptic::engine
