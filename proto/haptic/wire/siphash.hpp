#pragma once
// SipHash-2-4 (Aumasson & Bernstein, 2012): a keyed 64-bit tag for short messages.

#include <cstdint>
#include <span>

#include "haptic/wire/datagram.hpp"

namespace haptic::wire {

/// SipHash-2-4 of `message` under `key`, as in the reference implementation (little-endian).
std::uint64_t siphash24(const Key& key, std::span<const std::uint8_t> message);

}  // namespace haptic::wire
