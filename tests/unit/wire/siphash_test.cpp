// SipHash-2-4 against the reference implementation's test vectors (key 00 01 .. 0f, message
// 00 01 .. of length n; vectors.h of the reference code, read as little-endian 64-bit words).
#include <gtest/gtest.h>

#include <vector>

#include "haptic/wire/siphash.hpp"

namespace haptic::wire {
namespace {

TEST(SipHash24, ReferenceVectors) {
  Key key;
  for (int i = 0; i < 16; ++i) key[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(i);
  std::vector<std::uint8_t> message;
  auto of_length = [&](std::size_t n) {
    message.clear();
    for (std::size_t i = 0; i < n; ++i) message.push_back(static_cast<std::uint8_t>(i));
    return siphash24(key, message);
  };
  EXPECT_EQ(of_length(0), 0x726fdb47dd0e0e31ull);
  EXPECT_EQ(of_length(1), 0x74f839c593dc67fdull);
  EXPECT_EQ(of_length(2), 0x0d6c8009d9a94f5aull);
  EXPECT_EQ(of_length(3), 0x85676696d7fb7e2dull);
  EXPECT_EQ(of_length(63), 0x958a324ceb064572ull);
}

TEST(SipHash24, KeyAndEveryMessageByteMatter) {
  Key key{};
  std::vector<std::uint8_t> message(40, 0x5a);
  const std::uint64_t base = siphash24(key, message);
  for (std::size_t i = 0; i < message.size(); ++i) {
    message[i] ^= 1;
    EXPECT_NE(siphash24(key, message), base) << "byte " << i;
    message[i] ^= 1;
  }
  key[15] = 1;
  EXPECT_NE(siphash24(key, message), base);
}

}  // namespace
}  // namespace haptic::wire
