// Fuzz entry point for the datagram decoders: no input may crash them or read out of bounds, the
// decoders must agree with peek_header, and whatever decodes must re-encode to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "haptic/wire/datagram.hpp"

namespace {

// The replay driver signs its valid inputs with this key; libFuzzer finds none that verify, but
// still explores every check before the tag.
constexpr haptic::wire::Key kKey{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};

// abort() rather than assert(): the check must also hold in release builds.
void require(bool condition) {
  if (!condition) std::abort();
}

bool same_header(const haptic::wire::Header& a, const haptic::wire::Header& b) {
  return a.type == b.type && a.session_id == b.session_id && a.sequence == b.sequence &&
         a.time_ns == b.time_ns;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace haptic::wire;
  const std::span<const std::uint8_t> input(data, size);

  Header peeked;
  const DecodeError peek = peek_header(input, peeked);
  if (peek == DecodeError::kNone) {
    require(size == kStateDatagramSize || size == kHeartbeatDatagramSize ||
            size == kPathDatagramSize);
  }

  Header header;
  StatePayload state;
  const DecodeError state_result = decode_state(input, kKey, header, state);
  if (state_result == DecodeError::kNone) {
    require(peek == DecodeError::kNone && same_header(header, peeked));
    require(header.type == DatagramType::kState);
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
  return 0;
}
