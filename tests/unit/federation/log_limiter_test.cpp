// The federation's rate limit for lines that could repeat many times a second, on an injected
// clock: the first line of a key at once, the rest within the window counted, one summary when
// the window ends; keys apart.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "federation/log_limiter.hpp"

namespace haptic::federation {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

const LogLimiter::Clock::time_point t0 = LogLimiter::Clock::time_point{} + std::chrono::hours(1);

TEST(LogLimiter, TheFirstLineIsWrittenTheRestCountedAndSummarizedWhenTheWindowEnds) {
  LogLimiter limiter(seconds(10));
  std::vector<std::string> out;
  limiter.admit("b/item", "refused 1", t0, out);
  EXPECT_EQ(out, std::vector<std::string>{"refused 1"});
  for (int i = 2; i <= 39; ++i) limiter.admit("b/item", "refused " + std::to_string(i), t0 + milliseconds(i), out);
  EXPECT_EQ(out.size(), 1u) << "38 more within the window are counted, not written";
  EXPECT_EQ(limiter.pending(), 38u);
  limiter.flush(t0 + milliseconds(9999), out);
  EXPECT_EQ(out.size(), 1u) << "nothing before the window ends";
  limiter.flush(t0 + seconds(10), out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1], "refused 39 (and 37 more in 10 s)");
  EXPECT_EQ(limiter.pending(), 0u);
  // The summary opened the next window: a line 5 s later is counted, not written.
  limiter.admit("b/item", "refused 40", t0 + seconds(15), out);
  EXPECT_EQ(out.size(), 2u);
  // One counted line is summarized as itself, without a count.
  limiter.flush(t0 + seconds(20), out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2], "refused 40");
  // A whole window without a line: the key is forgotten and its next line written at once.
  limiter.flush(t0 + seconds(30), out);
  EXPECT_EQ(out.size(), 3u);
  limiter.admit("b/item", "refused 41", t0 + seconds(31), out);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[3], "refused 41");
}

TEST(LogLimiter, ALineAfterAnEndedWindowBringsItsSummaryWithoutAFlush) {
  LogLimiter limiter(seconds(10));
  std::vector<std::string> out;
  limiter.admit("k", "a", t0, out);
  limiter.admit("k", "b", t0 + seconds(1), out);
  limiter.admit("k", "c", t0 + seconds(2), out);
  limiter.admit("k", "d", t0 + seconds(12), out);  // the window has ended: its summary, d counted
  EXPECT_EQ(out, (std::vector<std::string>{"a", "c (and 1 more in 10 s)"}));
  EXPECT_EQ(limiter.pending(), 1u);
  // Quiet for a window after a line written: the next one is written at once.
  limiter.admit("q", "x", t0, out);
  limiter.admit("q", "y", t0 + seconds(10), out);
  EXPECT_EQ(out.back(), "y");
}

TEST(LogLimiter, KeysAreLimitedApart) {
  LogLimiter limiter(seconds(10));
  std::vector<std::string> out;
  limiter.admit("b/item", "b item", t0, out);
  limiter.admit("c/item", "c item", t0, out);
  limiter.admit("b/wrench", "b wrench", t0, out);
  limiter.admit("b/item", "b item", t0 + seconds(1), out);
  limiter.admit("b/item", "b item", t0 + seconds(2), out);
  EXPECT_EQ(out, (std::vector<std::string>{"b item", "c item", "b wrench"}));
  limiter.flush(t0 + seconds(10), out);
  EXPECT_EQ(out, (std::vector<std::string>{"b item", "c item", "b wrench", "b item (and 1 more in 10 s)"}));
}

TEST(LogLimiter, TheWindowsLengthIsSaidInTheSummary) {
  LogLimiter limiter(milliseconds(2500));
  std::vector<std::string> out;
  for (int i = 0; i < 4; ++i) limiter.admit("k", "same", t0, out);
  limiter.flush(t0 + milliseconds(2500), out);
  EXPECT_EQ(out, (std::vector<std::string>{"same", "same (and 2 more in 2.5 s)"}));
}

}  // namespace
}  // namespace haptic::federation
