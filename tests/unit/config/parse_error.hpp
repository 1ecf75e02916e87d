#pragma once
// What the configuration tests share: the error a JSON configuration is refused with.

#include <string>

#include "config/server_config.hpp"

namespace haptic::config {

/// The ConfigError parse_config throws for `json` (named "test.json"); empty when it is accepted.
inline std::string error_of(const std::string& json) {
  try {
    parse_config(json, "test.json");
  } catch (const ConfigError& error) {
    return error.what();
  }
  return {};
}

}  // namespace haptic::config
