// DDS domains for tests on loopback that no other test process on this machine uses at the same
// time. ctest runs tests in parallel, and two sites that meet in one domain on loopback discover
// each other and mix their samples: a domain taken from the process id (100 + pid mod 120, as
// before) collided when two federation tests started 30 pids apart, and each saw the other's
// sites. A domain is held by an advisory lock on a file of its own, which the kernel drops when
// the process exits however it ends. python/tests/dds_domain.py takes the same locks.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>

namespace haptic::test {

/// The domains tests take, and where their locks lie (one file per domain).
inline constexpr std::uint32_t kFirstTestDdsDomain = 100;
inline constexpr std::uint32_t kTestDdsDomains = 120;
inline constexpr const char* kTestDdsDomainLockPrefix = "/tmp/hapticd-test-dds-domain-";

/// A domain no other process holds, from 100 to 219, held until this process exits. Each call
/// takes another (a lock is per open file, so this process's own earlier ones are held too).
/// Throws std::runtime_error when all 120 are held.
inline std::uint32_t unique_dds_domain() {
  static std::mutex mutex;
  const std::lock_guard lock(mutex);
  for (std::uint32_t i = 0; i < kTestDdsDomains; ++i) {
    const std::uint32_t domain = kFirstTestDdsDomain + i;
    const std::string path = kTestDdsDomainLockPrefix + std::to_string(domain) + ".lock";
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    // Kept open on success: closing the file would drop the lock.
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;
    ::close(fd);
  }
  throw std::runtime_error(std::string("no free DDS domain for a test: all of ") + kTestDdsDomainLockPrefix +
                           "100…219.lock are held");
}

/// This process's one domain (taken on the first call): for the several participants of one
/// test that must meet.
inline std::uint32_t process_dds_domain() {
  static const std::uint32_t domain = unique_dds_domain();
  return domain;
}

}  // namespace haptic::test
