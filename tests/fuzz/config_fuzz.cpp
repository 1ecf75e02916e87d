// Fuzz entry point: hapticd's configuration file (protobuf's JSON mapping of ServerConfig, its
// defaults filled, every field validated, security included). Any text must either parse into a
// configuration that validates, or be refused with a ConfigError naming what was wrong; nothing
// else may escape, and a refusal must say something.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "config/server_config.hpp"
#include "fuzz/fuzz_seeds.hpp"

namespace haptic::fuzz {
std::vector<std::string> seeds() {
  return {"{}", R"({"time_mode": "LOCKSTEP", "loop_rate_hz": 2000})",
          R"({"security": {"tokens": [{"name": "a", "token": "0123456789abcdef", "role": "ADMIN"}]}})"};
}
}  // namespace haptic::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const haptic::v1::ServerConfig config = haptic::config::parse_config(text, "fuzz");
    // What was accepted validates again (validation is a pure function of the configuration).
    if (!haptic::config::validate(config).empty()) std::abort();
  } catch (const haptic::config::ConfigError& error) {
    if (std::string(error.what()).empty()) std::abort();
  }
  return 0;
}
