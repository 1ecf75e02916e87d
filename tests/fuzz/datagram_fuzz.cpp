// Fuzz entry point for the datagram decoders: no input may crash them or read out of bounds, the
// decoders must agree with peek_header, and whatever decodes must re-encode to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <array>
#include <span>

#include "haptic/wire/datagram.hpp"
#include "haptic/wire/siphash.hpp"

namespace {

// The key every input is decoded with, and signed with in the second pass.
constexpr haptic::wire::Key kKey{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

// abort() rather than assert(): the check must also hold in release builds.
void require(bool condition) {
  if (!condition) std::abort();
}

bool same_header(const haptic::wire::Header& a, const haptic::wire::Header& b) {
  return a.type == b.type && a.session_id == b.session_id && a.sequence == b.sequence &&
         a.time_ns == b.time_ns;
}

/// Every decoder on one input, and the properties they must keep together.
void check_datagram(std::span<const std::uint8_t> input) {
  using namespace haptic::wire;
  const std::uint8_t* data = input.data();
  const std::size_t size = input.size();

  Header peeked;
  const DecodeError peek = peek_header(input, peeked);
  if (peek == DecodeError::kNone) {
    require(size == kStateDatagramSize || size == kStateOrientedDatagramSize ||
            size == kHeartbeatDatagramSize || size == kPathDatagramSize);
  }

  Header header;
  StatePayload state;
  const DecodeError state_result = decode_state(input, kKey, header, state);
  if (state_result == DecodeError::kNone) {
    require(peek == DecodeError::kNone && same_header(header, peeked));
    require(header.type == (state.has_orientation ? DatagramType::kStateOriented : DatagramType::kState));
    std::uint8_t again[kMaxDatagramSize];
    require(encode_state(header, state, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  } else if (peek != DecodeError::kNone && peek != DecodeError::kUnknownType) {
    // A decoder reports the same header problem that peek_header found.
    require(state_result == peek);
  }

  HeartbeatPayload heartbeat;
  const DecodeError heartbeat_result = decode_heartbeat(input, kKey, header, heartbeat);
  if (heartbeat_result == DecodeError::kNone) {
    require(state_result != DecodeError::kNone);
    require(peek == DecodeError::kNone && same_header(header, peeked));
    require(header.type == DatagramType::kHeartbeat);
    std::uint8_t again[kMaxDatagramSize];
    require(encode_heartbeat(header, heartbeat, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  }

  PathChallengePayload challenge;
  const DecodeError challenge_result = decode_path_challenge(input, kKey, header, challenge);
  if (challenge_result == DecodeError::kNone) {
    require(state_result != DecodeError::kNone && heartbeat_result != DecodeError::kNone);
    require(peek == DecodeError::kNone && same_header(header, peeked));
    require(header.type == DatagramType::kPathChallenge);
    std::uint8_t again[kMaxDatagramSize];
    require(encode_path_challenge(header, challenge, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  } else if (peek != DecodeError::kNone && peek != DecodeError::kUnknownType) {
    require(challenge_result == peek);
  }

  PathResponsePayload response;
  const DecodeError response_result = decode_path_response(input, kKey, header, response);
  if (response_result == DecodeError::kNone) {
    require(challenge_result != DecodeError::kNone && heartbeat_result != DecodeError::kNone);
    require(peek == DecodeError::kNone && same_header(header, peeked));
    require(header.type == DatagramType::kPathResponse);
    std::uint8_t again[kMaxDatagramSize];
    require(encode_path_response(header, response, kKey, again) == size);
    require(std::memcmp(again, data, size) == 0);
  }
}

}  // namespace

// Each input twice: as it is, and signed, its last 8 bytes replaced by the tag of the rest under
// kKey. A fuzzer almost never guesses a SipHash tag, so unsigned inputs stop at the tag check;
// signed, they reach every payload decoder and the round trips behind it.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace haptic::wire;
  check_datagram({data, size});
  std::array<std::uint8_t, 4 * kMaxDatagramSize> signed_copy{};
  if (size >= kHeaderSize + kTagSize && size <= signed_copy.size()) {
    std::copy(data, data + size, signed_copy.begin());
    const std::size_t body = size - kTagSize;
    const std::uint64_t tag = siphash24(kKey, std::span<const std::uint8_t>(signed_copy.data(), body));
    for (std::size_t i = 0; i < kTagSize; ++i) signed_copy[body + i] = static_cast<std::uint8_t>(tag >> (8 * i));
    check_datagram({signed_copy.data(), size});
  }
  return 0;
}
