#pragma once
// What a byte-input fuzz target starts from besides its corpus folders: inputs it makes itself
// (valid messages, written out by `<replay> --seeds DIR` for libFuzzer's corpus).

#include <string>
#include <vector>

namespace haptic::fuzz {

/// Defined by each target.
std::vector<std::string> seeds();

}  // namespace haptic::fuzz
