// The tests' DDS domains (tests/support/dds_domain.hpp): never one that another process holds,
// another at each call, and the process's own the same at every call.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>

#include "support/dds_domain.hpp"

namespace haptic::test {
namespace {

bool in_range(std::uint32_t domain) {
  return domain >= kFirstTestDdsDomain && domain < kFirstTestDdsDomain + kTestDdsDomains;
}

TEST(TestDdsDomain, EachCallTakesAnotherAndTheProcesssOwnStays) {
  const std::uint32_t a = unique_dds_domain();
  const std::uint32_t b = unique_dds_domain();
  EXPECT_NE(a, b);
  EXPECT_TRUE(in_range(a) && in_range(b)) << a << ", " << b;
  const std::uint32_t own = process_dds_domain();
  EXPECT_EQ(process_dds_domain(), own);
  EXPECT_NE(own, a);
  EXPECT_NE(own, b);
}

TEST(TestDdsDomain, AnotherProcessNeverGetsOneThisProcessHolds) {
  const std::uint32_t held = unique_dds_domain();
  const std::uint32_t own = process_dds_domain();
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // A process of its own, as a parallel ctest job is.
    std::uint32_t domain = 0;
    try {
      domain = unique_dds_domain();
    } catch (...) {
    }
    const ssize_t written = ::write(pipe_fds[1], &domain, sizeof domain);
    ::_exit(written == sizeof domain ? 0 : 1);
  }
  std::uint32_t childs = 0;
  ASSERT_EQ(::read(pipe_fds[0], &childs, sizeof childs), static_cast<ssize_t>(sizeof childs));
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(pipe_fds[0]);
  ::close(pipe_fds[1]);
  EXPECT_TRUE(in_range(childs)) << childs;
  EXPECT_NE(childs, held);
  EXPECT_NE(childs, own);
}

}  // namespace
}  // namespace haptic::test
