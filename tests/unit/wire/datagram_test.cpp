// The UDP datagram codec: round trips, the byte layout, and every way a datagram is rejected.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "haptic/wire/datagram.hpp"

namespace haptic::wire {
namespace {

Key test_key() {
  Key key;
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(0xa0 + i);
  return key;
}

StatePayload sample_state() {
  StatePayload s;
  s.tick = 0xfedcba9876543210ull;
  s.p_WT = {0.01, -0.02, 0.03};
  s.v_WT = {std::numeric_limits<double>::infinity(), -0.0, 1e-300};
  s.F_T_W = {5.0, -5.0, std::numeric_limits<double>::max()};
  s.p_WP = {std::numeric_limits<double>::quiet_NaN(), 0.0, -1.5};
  s.contact_count = 3;
  s.flags = kFlagForceSaturated | kFlagRampingOut;
  return s;
}

Header sample_header() {
  Header h;
  h.session_id = 0x0123456789abcdefull;
  h.sequence = std::numeric_limits<std::uint64_t>::max();
  h.time_ns = -42;
  return h;
}

std::vector<std::uint8_t> encoded_state() {
  std::vector<std::uint8_t> out(kStateDatagramSize);
  EXPECT_EQ(encode_state(sample_header(), sample_state(), test_key(), out), kStateDatagramSize);
  return out;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Datagram, StateRoundTripIsBitExact) {
  const auto bytes = encoded_state();
  Header header;
  StatePayload state;
  ASSERT_EQ(decode_state(bytes, test_key(), header, state), DecodeError::kNone);
  EXPECT_EQ(header.type, DatagramType::kState);
  EXPECT_EQ(header.session_id, sample_header().session_id);
  EXPECT_EQ(header.sequence, sample_header().sequence);
  EXPECT_EQ(header.time_ns, -42);
  const StatePayload expected = sample_state();
  EXPECT_EQ(state.tick, expected.tick);
  EXPECT_TRUE(same_bits(state.v_WT.y, -0.0));
  EXPECT_TRUE(std::isnan(state.p_WP.x));
  EXPECT_EQ(state.F_T_W.z, std::numeric_limits<double>::max());
  EXPECT_EQ(state.p_WT, expected.p_WT);
  EXPECT_EQ(state.contact_count, 3u);
  EXPECT_EQ(state.flags, expected.flags);
}

TEST(Datagram, HeartbeatRoundTrip) {
  std::array<std::uint8_t, kHeartbeatDatagramSize> bytes{};
  HeartbeatPayload sent{-123456789, 77};
  Header h = sample_header();
  ASSERT_EQ(encode_heartbeat(h, sent, test_key(), bytes), kHeartbeatDatagramSize);
  Header header;
  HeartbeatPayload received;
  ASSERT_EQ(decode_heartbeat(bytes, test_key(), header, received), DecodeError::kNone);
  EXPECT_EQ(received, sent);
  EXPECT_EQ(header.type, DatagramType::kHeartbeat);
}

TEST(Datagram, LayoutIsLittleEndianAtDocumentedOffsets) {
  const auto b = encoded_state();
  EXPECT_EQ(b[0], 'H');
  EXPECT_EQ(b[1], 'P');
  EXPECT_EQ(b[2], 'T');
  EXPECT_EQ(b[3], 'C');
  EXPECT_EQ(b[4], kWireVersion & 0xff);
  EXPECT_EQ(b[5], 0);
  EXPECT_EQ(b[6], 1);  // type State
  EXPECT_EQ(b[8], 0xef);   // session id, least significant byte first
  EXPECT_EQ(b[15], 0x01);
  EXPECT_EQ(b[24], 0xd6);  // time_ns = -42
  EXPECT_EQ(b[32], kStatePayloadSize);
  EXPECT_EQ(b[40], 0x10);  // tick, least significant byte first
  EXPECT_EQ(kStateDatagramSize, 160u);
}

TEST(Datagram, RejectsMalformedDatagrams) {
  const auto good = encoded_state();
  Header header;
  StatePayload state;
  auto decode = [&](std::vector<std::uint8_t> bytes) {
    return decode_state(bytes, test_key(), header, state);
  };
  EXPECT_EQ(decode({}), DecodeError::kTooShort);
  EXPECT_EQ(decode(std::vector<std::uint8_t>(good.begin(), good.begin() + 20)), DecodeError::kTooShort);
  auto truncated = good;
  truncated.pop_back();
  EXPECT_EQ(decode(truncated), DecodeError::kBadPayloadSize);
  auto extended = good;
  extended.push_back(0);
  EXPECT_EQ(decode(extended), DecodeError::kBadPayloadSize);
  auto bad_magic = good;
  bad_magic[0] = 'X';
  EXPECT_EQ(decode(bad_magic), DecodeError::kBadMagic);
  auto bad_version = good;
  bad_version[4] = 9;
  EXPECT_EQ(decode(bad_version), DecodeError::kBadVersion);
  auto bad_type = good;
  bad_type[6] = 77;
  EXPECT_EQ(decode(bad_type), DecodeError::kUnknownType);
  auto bad_size = good;
  bad_size[32] = 1;
  EXPECT_EQ(decode(bad_size), DecodeError::kBadPayloadSize);
  auto bad_reserved = good;
  bad_reserved[37] = 1;
  EXPECT_EQ(decode(bad_reserved), DecodeError::kBadPayloadSize);
  Key other = test_key();
  other[0] ^= 1;
  EXPECT_EQ(decode_state(good, other, header, state), DecodeError::kBadTag);
}

TEST(Datagram, EverySingleBitFlipIsRejected) {
  const auto good = encoded_state();
  Header header;
  StatePayload state;
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    auto bytes = good;
    bytes[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    ASSERT_NE(decode_state(bytes, test_key(), header, state), DecodeError::kNone) << "bit " << bit;
  }
}

TEST(Datagram, HeartbeatIsNotAcceptedAsStateNorViceVersa) {
  std::array<std::uint8_t, kHeartbeatDatagramSize> heartbeat{};
  encode_heartbeat(sample_header(), HeartbeatPayload{}, test_key(), heartbeat);
  Header header;
  StatePayload state;
  EXPECT_EQ(decode_state(heartbeat, test_key(), header, state), DecodeError::kUnknownType);
  HeartbeatPayload hb;
  EXPECT_EQ(decode_heartbeat(encoded_state(), test_key(), header, hb), DecodeError::kUnknownType);
}

TEST(Datagram, EncoderRefusesASmallBuffer) {
  std::array<std::uint8_t, kStateDatagramSize - 1> small{};
  EXPECT_EQ(encode_state(sample_header(), sample_state(), test_key(), small), 0u);
  EXPECT_STRNE(to_string(DecodeError::kBadTag), "");
}

}  // namespace
}  // namespace haptic::wire
