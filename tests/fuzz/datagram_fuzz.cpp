// Fuzz entry point for the datagram decoders: no input may crash them or read out of bounds, and
// whatever decodes must re-encode to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "haptic/wire/datagram.hpp"

namespace {

constexpr haptic::wire::Key kKey{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

void require(bool condition) {
  if (!condition) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace haptic::wire;
  const std::span<const std::uint8_t> input(data, size);
  Header header;
  (void)peek_header(input, header);

  StatePayload state;
  if (decode_state(input, kKey, header, state) == DecodeError::kNone) {
    std::uint8_t again[kMaxDatagramSize];
    require(encode_state(header, state, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  }
  HeartbeatPayload heartbeat;
  if (decode_heartbeat(input, kKey, header, heartbeat) == DecodeError::kNone) {
    std::uint8_t again[kMaxDatagramSize];
    require(encode_heartbeat(header, heartbeat, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  }
  return 0;
}
