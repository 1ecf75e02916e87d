// A loop's CPU claimed host-wide, and the default choice that keeps two servers' loops apart.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <set>

#include "runtime/loop_cpu.hpp"

namespace haptic::runtime {
namespace {

// CPUs far above any real one, so that a server running on this host is never disturbed.
constexpr int kTestCpu = 4000;

TEST(LoopCpuClaim, ASecondClaimIsRefusedNamingTheHolderUntilTheFirstIsReleased) {
  std::optional<LoopCpuClaim> first = LoopCpuClaim::try_claim(kTestCpu);
  ASSERT_TRUE(first.has_value()) << LoopCpuClaim::lock_path(kTestCpu);
  EXPECT_EQ(first->cpu(), kTestCpu);
  pid_t holder = -1;
  EXPECT_FALSE(LoopCpuClaim::try_claim(kTestCpu, &holder).has_value());
  EXPECT_EQ(holder, ::getpid());
  EXPECT_TRUE(LoopCpuClaim::try_claim(kTestCpu + 1).has_value());  // another CPU is free
  LoopCpuClaim moved = std::move(*first);  // a move keeps the claim
  first.reset();
  EXPECT_FALSE(LoopCpuClaim::try_claim(kTestCpu).has_value());
  { LoopCpuClaim gone = std::move(moved); }
  EXPECT_TRUE(LoopCpuClaim::try_claim(kTestCpu).has_value());  // released with its holder
}

/// Claims against a set of CPUs held elsewhere, on the real lock files of test CPUs (from
/// `base`, so that tests running at once use files of their own).
struct Host {
  std::set<int> held_elsewhere;
  int base = kTestCpu + 10;
  std::optional<LoopCpuClaim> operator()(int cpu, pid_t* holder) const {
    if (held_elsewhere.count(cpu) != 0) {
      if (holder != nullptr) *holder = 4242;
      return std::nullopt;
    }
    return LoopCpuClaim::try_claim(base + cpu, holder);
  }
};

// The lock files go to the first folder every hapticd can write: /run/hapticd where the installed
// tmpfiles.d entry (or the unit's RuntimeDirectory) made it, else /run/lock.
TEST(LoopCpuClaim, TheLockFilesGoToTheFirstWritableOfTheCandidates) {
  const std::filesystem::path base = std::filesystem::temp_directory_path() /
                                     ("hapticd-lockdir-" + std::to_string(::getpid()));
  std::filesystem::create_directories(base / "writable");
  EXPECT_EQ(lock_directory_among({(base / "missing").string(), (base / "writable").string()}),
            (base / "writable").string());
  EXPECT_EQ(lock_directory_among({(base / "writable").string(), "/run/lock"}), (base / "writable").string());
  EXPECT_EQ(lock_directory_among({(base / "missing").string()}),
            std::filesystem::temp_directory_path().string());
  std::filesystem::remove_all(base);
  const std::string path = LoopCpuClaim::lock_path(3);
  EXPECT_EQ(path.substr(path.rfind('/')), "/hapticd-loop-cpu3.lock");
}

TEST(ChooseLoopCpu, TheDefaultTakesTheHighestFreeCpuAndWarnsOnlyWhenNoneIsLeft) {
  EXPECT_EQ(choose_loop_cpu(std::nullopt, 4, Host{}).cpu, 3);
  LoopCpuChoice second = choose_loop_cpu(std::nullopt, 4, Host{{3}});
  EXPECT_EQ(second.cpu, 2);  // a second server on the host goes elsewhere
  EXPECT_TRUE(second.claim.has_value());
  EXPECT_TRUE(second.warning.empty());
  const LoopCpuChoice crowded = choose_loop_cpu(std::nullopt, 2, Host{{0, 1}});
  EXPECT_EQ(crowded.cpu, 1);  // shares the last, and says so
  EXPECT_FALSE(crowded.claim.has_value());
  EXPECT_NE(crowded.warning.find("already runs another hapticd's loop: this one shares CPU 1"),
            std::string::npos)
      << crowded.warning;
  EXPECT_EQ(choose_loop_cpu(std::nullopt, 1, Host{}).cpu, -1);  // one CPU: nothing to pin
}

TEST(ChooseLoopCpu, AConfiguredCpuIsUsedEvenWhenHeldWithAWarningNamingTheHolder) {
  const Host host{{2}, kTestCpu + 20};
  const LoopCpuChoice held = choose_loop_cpu(2, 4, host);
  EXPECT_EQ(held.cpu, 2);
  EXPECT_NE(held.warning.find("real_time.cpu 2 already runs the loop of another hapticd (pid 4242)"),
            std::string::npos)
      << held.warning;
  const LoopCpuChoice free_cpu = choose_loop_cpu(1, 4, host);
  EXPECT_EQ(free_cpu.cpu, 1);
  EXPECT_TRUE(free_cpu.warning.empty());
  EXPECT_TRUE(free_cpu.claim.has_value());
  EXPECT_EQ(choose_loop_cpu(-1, 4, host).cpu, -1);  // no pinning asked for
}

}  // namespace
}  // namespace haptic::runtime
