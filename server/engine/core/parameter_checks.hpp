#pragma once
// The message every parameter struct's validate() returns for a bad value, in one form across
// the engine: "<name>: <requirement>, got <value>" (a vector as "(x, y, z)").

#include <cmath>
#include <sstream>
#include <string>
#include <string_view>

#include "engine/core/vec3.hpp"

namespace haptic::engine {

inline std::string bad_parameter(std::string_view name, std::string_view requirement,
                                 double value) {
  std::ostringstream out;
  out << name << ": " << requirement << ", got " << value;
  return out.str();
}

inline std::string bad_parameter(std::string_view name, std::string_view requirement,
                                 const Vec3& value) {
  std::ostringstream out;
  out << name << ": " << requirement << ", got (" << value.x << ", " << value.y << ", " << value.z
      << ")";
  return out.str();
}

inline bool is_positive(double v) { return std::isfinite(v) && v > 0.0; }
inline bool is_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace haptic::engine
