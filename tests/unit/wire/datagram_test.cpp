// The UDP datagram codec: round trips, the byte layout (docs/protocol.md), and every way a
// datagram is rejected.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "haptic/wire/datagram.hpp"
#include "haptic/wire/siphash.hpp"

namespace haptic::wire {
namespace {

using Bytes = std::vector<std::uint8_t>;

Key test_key() {
  Key key;
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(0xa0 + i);
  return key;
}

double from_bits(std::uint64_t bits) { return std::bit_cast<double>(bits); }
std::uint64_t bits_of(double v) { return std::bit_cast<std::uint64_t>(v); }

// Doubles chosen to catch any conversion on the way: a NaN with a payload, a signalling NaN,
// both infinities, -0.0, the smallest subnormal and the extremes.
StatePayload sample_state() {
  using limits = std::numeric_limits<double>;
  StatePayload s;
  s.tick = std::numeric_limits<std::uint64_t>::max();
  s.p_WT = {0.01, -0.02, 0.03};
  s.v_WT = {limits::infinity(), -0.0, limits::denorm_min()};
  s.F_T_W = {-limits::infinity(), -5.0, limits::max()};
  s.p_WP = {from_bits(0x7ff8'0000'dead'beefull), from_bits(0x7ff0'0000'0000'0001ull),
            from_bits(0xfff8'0000'0000'0000ull)};
  s.contact_count = std::numeric_limits<std::uint32_t>::max();
  s.flags = kFlagForceSaturated | kFlagRampingOut | (1u << 31);  // unknown bits pass through
  s.buttons = 0xdeadbeefu;
  return s;
}

Header sample_header() {
  Header h;
  h.session_id = std::numeric_limits<std::uint64_t>::max();
  h.sequence = std::numeric_limits<std::uint64_t>::max();
  h.time_ns = std::numeric_limits<std::int64_t>::min();
  return h;
}

Bytes encoded_state() {
  Bytes out(kStateDatagramSize);
  EXPECT_EQ(encode_state(sample_header(), sample_state(), test_key(), out), kStateDatagramSize);
  return out;
}

Bytes encoded_heartbeat() {
  Bytes out(kHeartbeatDatagramSize);
  const HeartbeatPayload hb{std::numeric_limits<std::int64_t>::max(), 77};
  EXPECT_EQ(encode_heartbeat(sample_header(), hb, test_key(), out), kHeartbeatDatagramSize);
  return out;
}

void expect_same_bits(const Vec3d& a, const Vec3d& b) {
  EXPECT_EQ(bits_of(a.x), bits_of(b.x));
  EXPECT_EQ(bits_of(a.y), bits_of(b.y));
  EXPECT_EQ(bits_of(a.z), bits_of(b.z));
}

DecodeError decode_as_state(const Bytes& bytes, const Key& key = test_key()) {
  Header header;
  StatePayload state;
  return decode_state(bytes, key, header, state);
}

DecodeError decode_as_heartbeat(const Bytes& bytes, const Key& key = test_key()) {
  Header header;
  HeartbeatPayload heartbeat;
  return decode_heartbeat(bytes, key, header, heartbeat);
}

// Rewrites the tag so that only the field under test is wrong.
void resign(Bytes& bytes) {
  const std::uint64_t tag =
      siphash24(test_key(), std::span(bytes).first(bytes.size() - kTagSize));
  for (std::size_t i = 0; i < kTagSize; ++i) {
    bytes[bytes.size() - kTagSize + i] = static_cast<std::uint8_t>(tag >> (8 * i));
  }
}

TEST(DatagramLayout, SizesMatchTheDocumentedLayout) {
  EXPECT_EQ(kHeaderSize, 40u);
  EXPECT_EQ(kStatePayloadSize, 116u);
  EXPECT_EQ(kStateOrientedPayloadSize, 172u);
  EXPECT_EQ(kHeartbeatPayloadSize, 48u);
  EXPECT_EQ(kStateDatagramSize, 164u);
  EXPECT_EQ(kStateOrientedDatagramSize, 220u);
  EXPECT_EQ(kHeartbeatDatagramSize, 96u);
  EXPECT_EQ(kMaxDatagramSize, 220u);
}

// The golden datagrams' key, 00 01 .. 0f, and header (the type is the encoder's).
Key golden_key() {
  Key key;
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(i);
  return key;
}

Header golden_header(std::uint64_t sequence, std::int64_t time_ns) {
  Header h;
  h.session_id = 0x0123456789abcdefull;
  h.sequence = sequence;
  h.time_ns = time_ns;
  return h;
}

// A complete heartbeat under golden_key(); the tag was computed by an independent SipHash-2-4
// implementation, so this pins layout and tag together.
TEST(DatagramLayout, HeartbeatMatchesGoldenBytes) {
  constexpr std::array<std::uint8_t, kHeartbeatDatagramSize> kGolden = {
      0x48, 0x50, 0x54, 0x43, 0x05, 0x00, 0x02, 0x00,  // "HPTC", version 5, type 2
      0xef, 0xcd, 0xab, 0x89, 0x67, 0x45, 0x23, 0x01,  // session_id
      0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // sequence 1
      0xd6, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,  // time_ns -42
      0x30, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // payload_size 48, reserved 0
      0x00, 0xca, 0x9a, 0x3b, 0x00, 0x00, 0x00, 0x00,  // client_time_ns 1e9
      0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // last_state_sequence 7
      0x06, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // states_received 6
      0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // states_lost 1
      0xc0, 0xb4, 0xb3, 0xff, 0xff, 0xff, 0xff, 0xff,  // echo_state_time_ns -5e6
      0x90, 0xd0, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00,  // echo_hold_ns 250000
      0x65, 0x4d, 0xfb, 0xd0, 0x54, 0x6b, 0x45, 0xd0,  // SipHash-2-4 tag
  };
  const Key key = golden_key();
  std::array<std::uint8_t, kHeartbeatDatagramSize> out{};
  ASSERT_EQ(encode_heartbeat(golden_header(1, -42),
                             HeartbeatPayload{1'000'000'000, 7, 6, 1, -5'000'000, 250'000}, key, out),
            kHeartbeatDatagramSize);
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i], kGolden[i]) << "offset " << i;

  Header header;
  HeartbeatPayload heartbeat;
  ASSERT_EQ(decode_heartbeat(kGolden, key, header, heartbeat), DecodeError::kNone);
  EXPECT_EQ(heartbeat, (HeartbeatPayload{1'000'000'000, 7, 6, 1, -5'000'000, 250'000}));
}

// A complete StateOriented under golden_key(), the tag again from an independent SipHash-2-4:
// State's fields, then R_WT and tau_T_W (wire version 5).
TEST(DatagramLayout, StateOrientedMatchesGoldenBytes) {
  constexpr std::array<std::uint8_t, kStateOrientedDatagramSize> kGolden = {
      0x48, 0x50, 0x54, 0x43,                           // "HPTC"
      0x05, 0x00,                                       // version 5
      0x05, 0x00,                                       // type 5, StateOriented
      0xef, 0xcd, 0xab, 0x89, 0x67, 0x45, 0x23, 0x01,   // session_id
      0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,   // sequence 3
      0x40, 0x42, 0x0f, 0x00, 0x00, 0x00, 0x00, 0x00,   // time_ns 1e6
      0xac, 0x00, 0x00, 0x00,                           // payload_size 172
      0x00, 0x00, 0x00, 0x00,                           // reserved
      0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,   // tick 7
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f,   // p_WT (1, 0, 0)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,   // v_WT 0
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,   // F_T_W (0, 0, -2)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xc0,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0x3f,   // p_WP (1, 0, 0)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x01, 0x00, 0x00, 0x00,                           // contact_count 1
      0x00, 0x00, 0x00, 0x00,                           // flags 0
      0x02, 0x00, 0x00, 0x00,                           // buttons 0b10
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f,   // R_WT (0.5, 0.5, -0.5, 0.5)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0xbf,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,   // tau_T_W (0, 0.25, -1)
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xd0, 0x3f,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf0, 0xbf,
      0x6a, 0x97, 0x9e, 0x59, 0xd9, 0xe1, 0x89, 0xc8,   // SipHash-2-4 tag
  };
  const Key key = golden_key();
  StatePayload s;
  s.tick = 7;
  s.p_WT = {1.0, 0.0, 0.0};
  s.F_T_W = {0.0, 0.0, -2.0};
  s.p_WP = {1.0, 0.0, 0.0};
  s.contact_count = 1;
  s.buttons = 0b10;
  s.has_orientation = true;
  s.R_WT = {0.5, 0.5, -0.5, 0.5};
  s.tau_T_W = {0.0, 0.25, -1.0};
  std::array<std::uint8_t, kStateOrientedDatagramSize> out{};
  ASSERT_EQ(encode_state(golden_header(3, 1'000'000), s, key, out), kStateOrientedDatagramSize);
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i], kGolden[i]) << "offset " << i;

  Header header;
  StatePayload state;
  ASSERT_EQ(decode_state(kGolden, key, header, state), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kStateOriented);
  EXPECT_EQ(state, s);
}

TEST(DatagramLayout, PathChallengeAndResponseAreShorterThanAHeartbeat) {
  // A challenge answers a heartbeat: no longer, so reflecting off the server amplifies nothing.
  EXPECT_EQ(kPathPayloadSize, 16u);
  EXPECT_EQ(kPathDatagramSize, 64u);
  EXPECT_LT(kPathDatagramSize, kHeartbeatDatagramSize);
}

TEST(DatagramRoundTrip, PathChallengeAndResponseAreBitExactAndNotEachOther) {
  Key key;
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(3 * i + 1);
  Header h;
  h.session_id = 0xfeedfacecafebeefull;
  h.sequence = 41;
  h.time_ns = 123;
  std::array<std::uint8_t, kPathDatagramSize> challenge{}, response{};
  ASSERT_EQ(encode_path_challenge(h, {0x8000000000000001ull, 40}, key, challenge), kPathDatagramSize);
  ASSERT_EQ(encode_path_response(h, {0x8000000000000001ull, -7}, key, response), kPathDatagramSize);
  EXPECT_EQ(challenge[6], 3);  // type at offset 6
  EXPECT_EQ(response[6], 4);
  EXPECT_EQ(challenge[40], 0x01);  // nonce, little-endian, first in the payload
  EXPECT_EQ(challenge[47], 0x80);
  Header header;
  PathChallengePayload c;
  PathResponsePayload r;
  ASSERT_EQ(decode_path_challenge(challenge, key, header, c), DecodeError::kNone);
  EXPECT_EQ(c, (PathChallengePayload{0x8000000000000001ull, 40}));
  EXPECT_EQ(header.type, DatagramType::kPathChallenge);
  EXPECT_EQ(header.sequence, 41u);
  ASSERT_EQ(decode_path_response(response, key, header, r), DecodeError::kNone);
  EXPECT_EQ(r, (PathResponsePayload{0x8000000000000001ull, -7}));
  // Neither passes for the other, nor for a heartbeat; a flipped bit breaks the tag.
  EXPECT_EQ(decode_path_response(challenge, key, header, r), DecodeError::kUnknownType);
  EXPECT_EQ(decode_path_challenge(response, key, header, c), DecodeError::kUnknownType);
  HeartbeatPayload hb;
  EXPECT_EQ(decode_heartbeat(response, key, header, hb), DecodeError::kUnknownType);
  for (std::size_t bit = 0; bit < 8 * kPathDatagramSize; ++bit) {
    auto flipped = response;
    flipped[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    EXPECT_NE(decode_path_response(flipped, key, header, r), DecodeError::kNone) << "bit " << bit;
  }
}

TEST(DatagramLayout, StateFieldsAreLittleEndianAtDocumentedOffsets) {
  Header h;
  h.session_id = 0x0123456789abcdefull;
  h.sequence = 2;
  h.time_ns = 5;
  StatePayload s;
  s.tick = 0x0102030405060708ull;
  s.p_WT.x = 1.0;  // 0x3ff0000000000000
  s.p_WP.z = -2.0;  // 0xc000000000000000
  s.contact_count = 0xa1b2c3d4u;
  s.flags = kFlagForceFault;
  s.buttons = 0x00000005u;
  Bytes b(kStateDatagramSize);
  ASSERT_EQ(encode_state(h, s, test_key(), b), kStateDatagramSize);

  EXPECT_EQ(b[0], 'H');
  EXPECT_EQ(b[1], 'P');
  EXPECT_EQ(b[2], 'T');
  EXPECT_EQ(b[3], 'C');
  EXPECT_EQ(b[4], kWireVersion & 0xff);
  EXPECT_EQ(b[5], kWireVersion >> 8);
  EXPECT_EQ(b[6], 1);  // type State
  EXPECT_EQ(b[7], 0);
  EXPECT_EQ(b[8], 0xef);  // session id, least significant byte first
  EXPECT_EQ(b[15], 0x01);
  EXPECT_EQ(b[16], 2);  // sequence
  EXPECT_EQ(b[24], 5);  // time_ns
  EXPECT_EQ(b[32], kStatePayloadSize);
  EXPECT_EQ(b[33], 0);
  for (std::size_t i = 36; i < 40; ++i) EXPECT_EQ(b[i], 0) << "reserved byte " << i;
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(b[40 + i], 8 - i) << "tick byte " << i;
  EXPECT_EQ(b[48 + 6], 0xf0);  // p_WT.x
  EXPECT_EQ(b[48 + 7], 0x3f);
  EXPECT_EQ(b[120 + 16 + 7], 0xc0);  // p_WP.z, the last double
  EXPECT_EQ(b[144], 0xd4);  // contact_count
  EXPECT_EQ(b[147], 0xa1);
  EXPECT_EQ(b[148], kFlagForceFault);  // flags
  EXPECT_EQ(b[152], 0x05);             // buttons
  EXPECT_EQ(b[155], 0x00);

  const std::uint64_t tag = siphash24(test_key(), std::span(b).first(156));
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(b[156 + i], static_cast<std::uint8_t>(tag >> (8 * i))) << "tag byte " << i;
  }
}

TEST(DatagramRoundTrip, StateIsBitExact) {
  const Bytes bytes = encoded_state();
  Header header;
  StatePayload state;
  ASSERT_EQ(decode_state(bytes, test_key(), header, state), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kState);
  EXPECT_EQ(header.session_id, sample_header().session_id);
  EXPECT_EQ(header.sequence, sample_header().sequence);
  EXPECT_EQ(header.time_ns, sample_header().time_ns);
  const StatePayload expected = sample_state();
  EXPECT_EQ(state.tick, expected.tick);
  expect_same_bits(state.p_WT, expected.p_WT);
  expect_same_bits(state.v_WT, expected.v_WT);
  expect_same_bits(state.F_T_W, expected.F_T_W);
  expect_same_bits(state.p_WP, expected.p_WP);
  EXPECT_EQ(state.contact_count, expected.contact_count);
  EXPECT_EQ(state.flags, expected.flags);
  EXPECT_EQ(state.buttons, expected.buttons);
  // A device without orientation: 56 bytes shorter, identity and no torque.
  EXPECT_FALSE(state.has_orientation);
  EXPECT_EQ(state.R_WT, Quatd{});
  EXPECT_EQ(state.tau_T_W, Vec3d{});
}

// The torque travels only with the orientation: State leaves it out, whatever the payload held.
TEST(DatagramRoundTrip, StateWithoutOrientationCarriesNoTorque) {
  StatePayload s = sample_state();
  s.tau_T_W = {1.0, 2.0, 3.0};
  Bytes b(kStateDatagramSize);
  ASSERT_EQ(encode_state(sample_header(), s, test_key(), b), kStateDatagramSize);
  EXPECT_EQ(b, encoded_state());
}

// A device that measures the tool's orientation: StateOriented, State's fields at the same
// offsets, then R_WT (w, x, y, z) at 156, tau_T_W (x, y, z) at 188, then the tag at 212.
TEST(DatagramLayout, StateOrientedAppendsTheOrientationAndTheTorque) {
  StatePayload s = sample_state();
  s.has_orientation = true;
  s.R_WT = {0.5, -0.5, from_bits(0x7ff8'0000'0000'0abcull), -0.0};
  s.tau_T_W = {-0.25, std::numeric_limits<double>::infinity(), from_bits(0x7ff0'0000'0000'0002ull)};
  Bytes b(kStateOrientedDatagramSize);
  ASSERT_EQ(encode_state(sample_header(), s, test_key(), b), kStateOrientedDatagramSize);
  EXPECT_EQ(b[6], 5);  // type StateOriented
  EXPECT_EQ(b[32], kStateOrientedPayloadSize);
  EXPECT_EQ(b[152], 0xef);  // buttons, as in State
  EXPECT_EQ(b[156 + 7], 0x3f);  // w = 0.5: 0x3fe0000000000000
  EXPECT_EQ(b[156 + 6], 0xe0);
  EXPECT_EQ(b[164 + 7], 0xbf);  // x = -0.5
  EXPECT_EQ(b[180 + 7], 0x80);  // z = -0.0
  EXPECT_EQ(b[188 + 7], 0xbf);  // tau_T_W.x = -0.25: 0xbfd0000000000000
  EXPECT_EQ(b[188 + 6], 0xd0);
  EXPECT_EQ(b[196 + 7], 0x7f);  // tau_T_W.y = +inf: 0x7ff0000000000000
  EXPECT_EQ(b[196 + 6], 0xf0);
  EXPECT_EQ(b[204], 0x02);      // tau_T_W.z, a signalling NaN's payload
  const std::uint64_t tag = siphash24(test_key(), std::span(b).first(212));
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(b[212 + i], static_cast<std::uint8_t>(tag >> (8 * i))) << "tag byte " << i;
  }
  Header header;
  StatePayload state;
  ASSERT_EQ(decode_state(b, test_key(), header, state), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kStateOriented);
  EXPECT_TRUE(state.has_orientation);
  EXPECT_EQ(bits_of(state.R_WT.w), bits_of(s.R_WT.w));
  EXPECT_EQ(bits_of(state.R_WT.x), bits_of(s.R_WT.x));
  EXPECT_EQ(bits_of(state.R_WT.y), bits_of(s.R_WT.y));
  EXPECT_EQ(bits_of(state.R_WT.z), bits_of(s.R_WT.z));
  expect_same_bits(state.tau_T_W, s.tau_T_W);
  EXPECT_EQ(state.buttons, s.buttons);
  // Too small a buffer for the oriented form writes nothing.
  Bytes small(kStateDatagramSize);
  EXPECT_EQ(encode_state(sample_header(), s, test_key(), small), 0u);
  // The oriented header on State's length (or the reverse) is refused.
  Bytes cut(b.begin(), b.begin() + kStateDatagramSize);
  EXPECT_EQ(decode_as_state(cut), DecodeError::kBadPayloadSize);
  // Version 4's StateOriented (148 payload bytes, no torque) under a version-5 header: refused.
  Bytes v4(b.begin(), b.begin() + kHeaderSize + 148 + kTagSize);
  v4[32] = 148;
  resign(v4);
  EXPECT_EQ(decode_as_state(v4), DecodeError::kBadPayloadSize);
}

TEST(DatagramRoundTrip, HeartbeatWithExtremeValues) {
  for (const HeartbeatPayload sent :
       {HeartbeatPayload{0, 0}, HeartbeatPayload{-123456789, 77, 70, 7, 12345, 67890},
        HeartbeatPayload{std::numeric_limits<std::int64_t>::min(),
                         std::numeric_limits<std::uint64_t>::max(),
                         std::numeric_limits<std::uint64_t>::max(), 0,
                         std::numeric_limits<std::int64_t>::min(),
                         std::numeric_limits<std::int64_t>::max()},
        HeartbeatPayload{std::numeric_limits<std::int64_t>::max(), 1, 1, 0, -1, 0}}) {
    Bytes bytes(kHeartbeatDatagramSize);
    ASSERT_EQ(encode_heartbeat(sample_header(), sent, test_key(), bytes), kHeartbeatDatagramSize);
    Header header;
    HeartbeatPayload received;
    ASSERT_EQ(decode_heartbeat(bytes, test_key(), header, received), DecodeError::kNone);
    EXPECT_EQ(received, sent);
    EXPECT_EQ(header.type, DatagramType::kHeartbeat);
    EXPECT_EQ(header.session_id, sample_header().session_id);
    EXPECT_EQ(header.sequence, sample_header().sequence);
    EXPECT_EQ(header.time_ns, sample_header().time_ns);
  }
}

TEST(DatagramRoundTrip, PeekHeaderReadsTheHeaderOfBothTypes) {
  Header header;
  ASSERT_EQ(peek_header(encoded_state(), header), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kState);
  EXPECT_EQ(header.session_id, sample_header().session_id);
  ASSERT_EQ(peek_header(encoded_heartbeat(), header), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kHeartbeat);
  EXPECT_EQ(header.time_ns, sample_header().time_ns);
}

// The encoder sets the type from the function, whatever the caller put in the header.
TEST(DatagramEncode, TypeComesFromTheEncoder) {
  Header h = sample_header();
  h.type = DatagramType::kHeartbeat;
  Bytes bytes(kStateDatagramSize);
  ASSERT_EQ(encode_state(h, sample_state(), test_key(), bytes), kStateDatagramSize);
  EXPECT_EQ(decode_as_state(bytes), DecodeError::kNone);
}

TEST(DatagramEncode, WritesExactlyTheDatagramIntoALargerBuffer) {
  Bytes big(kStateDatagramSize + 10, 0xcc);
  ASSERT_EQ(encode_state(sample_header(), sample_state(), test_key(), big), kStateDatagramSize);
  for (std::size_t i = kStateDatagramSize; i < big.size(); ++i) EXPECT_EQ(big[i], 0xcc);
  big.resize(kStateDatagramSize);
  EXPECT_EQ(big, encoded_state());
}

TEST(DatagramEncode, RefusesASmallBufferAndWritesNothing) {
  Bytes small(kStateDatagramSize - 1, 0xcc);
  EXPECT_EQ(encode_state(sample_header(), sample_state(), test_key(), small), 0u);
  EXPECT_EQ(small, Bytes(kStateDatagramSize - 1, 0xcc));
  Bytes small_hb(kHeartbeatDatagramSize - 1, 0xcc);
  EXPECT_EQ(encode_heartbeat(sample_header(), HeartbeatPayload{}, test_key(), small_hb), 0u);
  EXPECT_EQ(small_hb, Bytes(kHeartbeatDatagramSize - 1, 0xcc));
  EXPECT_EQ(encode_heartbeat(sample_header(), HeartbeatPayload{}, test_key(), {}), 0u);
}

TEST(DatagramReject, TooShort) {
  const Bytes good = encoded_state();
  Header header;
  EXPECT_EQ(decode_as_state({}), DecodeError::kTooShort);
  EXPECT_EQ(peek_header({}, header), DecodeError::kTooShort);
  EXPECT_EQ(decode_as_state(Bytes(good.begin(), good.begin() + 20)), DecodeError::kTooShort);
  EXPECT_EQ(decode_as_state(Bytes(good.begin(), good.begin() + kHeaderSize + kTagSize - 1)),
            DecodeError::kTooShort);
  EXPECT_EQ(decode_as_heartbeat(Bytes(kHeaderSize, 0)), DecodeError::kTooShort);
}

TEST(DatagramReject, BadMagic) {
  for (std::size_t i = 0; i < 4; ++i) {
    Bytes bytes = encoded_state();
    bytes[i] ^= 0x20;  // "hPTC" etc.
    resign(bytes);
    EXPECT_EQ(decode_as_state(bytes), DecodeError::kBadMagic) << "byte " << i;
  }
}

TEST(DatagramReject, BadVersion) {
  // 1: before path validation; 2: before buttons and StateOriented; 3: before the heartbeat's
  // receive report; 4: before the torque in StateOriented.
  for (const std::uint16_t version : {0, 1, 2, 3, 4, 6, 0x0100, 0xffff}) {
    Bytes bytes = encoded_heartbeat();
    bytes[4] = static_cast<std::uint8_t>(version);
    bytes[5] = static_cast<std::uint8_t>(version >> 8);
    resign(bytes);
    EXPECT_EQ(decode_as_heartbeat(bytes), DecodeError::kBadVersion) << "version " << version;
    Header header;
    EXPECT_EQ(peek_header(bytes, header), DecodeError::kBadVersion);
  }
}

TEST(DatagramReject, UnknownType) {
  for (const std::uint16_t type : {0, 6, 0x0101, 0xffff}) {
    Bytes bytes = encoded_state();
    bytes[6] = static_cast<std::uint8_t>(type);
    bytes[7] = static_cast<std::uint8_t>(type >> 8);
    resign(bytes);
    EXPECT_EQ(decode_as_state(bytes), DecodeError::kUnknownType) << "type " << type;
    Header header;
    EXPECT_EQ(peek_header(bytes, header), DecodeError::kUnknownType);
  }
}

TEST(DatagramReject, PayloadSizeThatDoesNotMatchTheType) {
  Bytes bytes = encoded_state();
  bytes[32] = kHeartbeatPayloadSize;
  resign(bytes);
  EXPECT_EQ(decode_as_state(bytes), DecodeError::kBadPayloadSize);
  bytes[32] = kStatePayloadSize;
  bytes[34] = 1;  // 116 + 65536
  resign(bytes);
  EXPECT_EQ(decode_as_state(bytes), DecodeError::kBadPayloadSize);

  // A heartbeat header stretched to a state's length, its payload_size claiming 116.
  Bytes stretched = encoded_heartbeat();
  stretched.resize(kStateDatagramSize);
  stretched[32] = kStatePayloadSize;
  resign(stretched);
  EXPECT_EQ(decode_as_heartbeat(stretched), DecodeError::kBadPayloadSize);
}

TEST(DatagramReject, NonzeroReserved) {
  for (std::size_t i = 36; i < 40; ++i) {
    Bytes bytes = encoded_state();
    bytes[i] = 0x80;
    resign(bytes);
    EXPECT_EQ(decode_as_state(bytes), DecodeError::kBadPayloadSize) << "byte " << i;
    Header header;
    EXPECT_EQ(peek_header(bytes, header), DecodeError::kBadPayloadSize);
  }
}

TEST(DatagramReject, TrailingBytes) {
  Bytes extended = encoded_state();
  extended.push_back(0);
  EXPECT_EQ(decode_as_state(extended), DecodeError::kBadPayloadSize);
  Header header;
  EXPECT_EQ(peek_header(extended, header), DecodeError::kBadPayloadSize);
  Bytes hb = encoded_heartbeat();
  hb.insert(hb.end(), 8, 0);
  EXPECT_EQ(decode_as_heartbeat(hb), DecodeError::kBadPayloadSize);
}

TEST(DatagramReject, TruncatedByOneByte) {
  Bytes state = encoded_state();
  state.pop_back();
  EXPECT_EQ(decode_as_state(state), DecodeError::kBadPayloadSize);
  Bytes hb = encoded_heartbeat();
  hb.pop_back();
  EXPECT_EQ(decode_as_heartbeat(hb), DecodeError::kBadPayloadSize);
}

// Every length but the exact one fails, for both decoders and peek_header.
TEST(DatagramReject, EveryOtherLength) {
  const Bytes state = encoded_state();
  const Bytes hb = encoded_heartbeat();
  for (std::size_t n = 0; n < kMaxDatagramSize + 32; ++n) {
    Bytes s = state;
    s.resize(n);
    Bytes h = hb;
    h.resize(n);
    Header header;
    if (n != kStateDatagramSize) {
      EXPECT_NE(decode_as_state(s), DecodeError::kNone) << "length " << n;
      EXPECT_NE(peek_header(s, header), DecodeError::kNone) << "length " << n;
    }
    if (n != kHeartbeatDatagramSize) {
      EXPECT_NE(decode_as_heartbeat(h), DecodeError::kNone) << "length " << n;
      EXPECT_NE(peek_header(h, header), DecodeError::kNone) << "length " << n;
    }
  }
}

TEST(DatagramReject, EverySingleBitFlipInAState) {
  const Bytes good = encoded_state();
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    Bytes bytes = good;
    bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    ASSERT_NE(decode_as_state(bytes), DecodeError::kNone) << "bit " << bit;
  }
}

TEST(DatagramReject, EverySingleBitFlipInAHeartbeat) {
  const Bytes good = encoded_heartbeat();
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    Bytes bytes = good;
    bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    ASSERT_NE(decode_as_heartbeat(bytes), DecodeError::kNone) << "bit " << bit;
  }
}

TEST(DatagramReject, WrongKey) {
  for (std::size_t bit = 0; bit < sizeof(Key) * 8; ++bit) {
    Key other = test_key();
    other[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    ASSERT_EQ(decode_as_state(encoded_state(), other), DecodeError::kBadTag) << "key bit " << bit;
    ASSERT_EQ(decode_as_heartbeat(encoded_heartbeat(), other), DecodeError::kBadTag);
  }
}

// peek_header exists to find the key, so it must not need it: a forged tag still peeks.
TEST(DatagramReject, PeekHeaderDoesNotCheckTheTag) {
  Bytes bytes = encoded_state();
  bytes.back() ^= 1;
  Header header;
  EXPECT_EQ(peek_header(bytes, header), DecodeError::kNone);
  EXPECT_EQ(decode_as_state(bytes), DecodeError::kBadTag);
}

TEST(DatagramReject, HeartbeatIsNotAcceptedAsStateNorViceVersa) {
  EXPECT_EQ(decode_as_state(encoded_heartbeat()), DecodeError::kUnknownType);
  EXPECT_EQ(decode_as_heartbeat(encoded_state()), DecodeError::kUnknownType);
}

TEST(DatagramReject, OutputsAreUntouchedOnFailure) {
  Bytes bytes = encoded_state();
  bytes[bytes.size() - 1] ^= 1;  // bad tag: everything before it parses
  Header header;
  header.session_id = 5;
  StatePayload state;
  state.tick = 6;
  ASSERT_EQ(decode_state(bytes, test_key(), header, state), DecodeError::kBadTag);
  EXPECT_EQ(header.session_id, 5u);
  EXPECT_EQ(state.tick, 6u);

  Bytes reserved = encoded_heartbeat();
  reserved[36] = 1;
  HeartbeatPayload heartbeat{8, 9};
  ASSERT_EQ(peek_header(reserved, header), DecodeError::kBadPayloadSize);
  ASSERT_EQ(decode_heartbeat(reserved, test_key(), header, heartbeat), DecodeError::kBadPayloadSize);
  EXPECT_EQ(header.session_id, 5u);
  EXPECT_EQ(heartbeat, (HeartbeatPayload{8, 9}));
}

TEST(DecodeErrorNames, AreShortDistinctAndNeverNull) {
  std::set<std::string> names;
  for (const DecodeError e :
       {DecodeError::kNone, DecodeError::kTooShort, DecodeError::kBadMagic,
        DecodeError::kBadVersion, DecodeError::kUnknownType, DecodeError::kBadPayloadSize,
        DecodeError::kBadTag}) {
    const char* name = to_string(e);
    ASSERT_NE(name, nullptr);
    EXPECT_FALSE(std::string(name).empty());
    EXPECT_LE(std::string(name).size(), 20u);
    names.insert(name);
  }
  EXPECT_EQ(names.size(), 7u);
  EXPECT_STREQ(to_string(DecodeError::kBadTag), "bad tag");
  EXPECT_NE(to_string(static_cast<DecodeError>(200)), nullptr);
}

}  // namespace
}  // namespace haptic::wire
