// Which hosts count as this host's own (haptic/io/loopback): the SDK sends a token in clear only to
// those, and a federation interface off them needs DDS Security. Decided from the text alone: a
// name other than localhost is never loopback, whatever it might resolve to.
#include <gtest/gtest.h>

#include "haptic/io/loopback.hpp"

namespace haptic::io {
namespace {

TEST(Loopback, NumericLoopbackAddressesAndLocalhostAreThisHost) {
  for (const char* host : {"127.0.0.1", "127.255.0.9", "::1", "[::1]", "::ffff:127.0.0.1",
                           "[::ffff:127.1.2.3]", "localhost", "LocalHost"}) {
    EXPECT_TRUE(is_loopback_literal(host)) << host;
  }
}

TEST(Loopback, AnythingElseIsNotEvenWhenItLooksLikeIt) {
  for (const char* host : {"10.0.127.1", "127.example.com", "127.0.0.1.example.com", "0.0.0.0", "::",
                           "128.0.0.1", "::ffff:10.0.0.1", "localhost.example.com", "127.1", "",
                           "eth0", "[127.0.0.1"}) {
    EXPECT_FALSE(is_loopback_literal(host)) << host;
  }
}

}  // namespace
}  // namespace haptic::io
