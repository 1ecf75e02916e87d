#pragma once
// Which CPU a real-time loop runs on, host-wide: several hapticd on one host (a lab with two
// devices) must not put their loops on one core without saying so. Each loop claims its CPU with
// an flock on a file named after it (in /run/hapticd where the installed tmpfiles.d entry or
// hapticd.service made it, else /run/lock, else the temporary directory); the lock goes with the
// process, however it ends. Servers in containers with private /run and /tmp do not see
// each other's claims: give each its `real_time.cpu` there.

#include <functional>
#include <optional>
#include <string>
#include <sys/types.h>
#include <vector>

namespace haptic::runtime {

/// The first of `candidates` this process may write in, else the temporary directory: where the
/// lock files go (LoopCpuClaim::lock_path asks with /run/hapticd, then /run/lock).
std::string lock_directory_among(const std::vector<std::string>& candidates);

/// A held claim on one CPU for a loop. Move-only; released when destroyed.
class LoopCpuClaim {
 public:
  /// Claims `cpu` (>= 0). Empty when another process (or another claim in this one) holds it;
  /// then `holder` is its pid as it wrote it (0 if unknown).
  static std::optional<LoopCpuClaim> try_claim(int cpu, pid_t* holder = nullptr);

  LoopCpuClaim(LoopCpuClaim&& other) noexcept;
  LoopCpuClaim& operator=(LoopCpuClaim&& other) noexcept;
  LoopCpuClaim(const LoopCpuClaim&) = delete;
  LoopCpuClaim& operator=(const LoopCpuClaim&) = delete;
  ~LoopCpuClaim();

  int cpu() const { return cpu_; }

  /// The file that marks `cpu` (for messages and tests).
  static std::string lock_path(int cpu);

 private:
  LoopCpuClaim(int cpu, int fd) : cpu_(cpu), fd_(fd) {}
  int cpu_ = -1;
  int fd_ = -1;
};

/// The CPU chosen for a loop, and what the server should say about it.
struct LoopCpuChoice {
  int cpu = -1;                        // -1: not pinned
  std::optional<LoopCpuClaim> claim;   // held while the loop runs
  std::string warning;                 // non-empty: log it
};

/// Chooses the loop's CPU. `configured`: real_time.cpu when set (-1: no pinning), empty for the
/// default, which is the highest-numbered CPU no other loop has claimed (from cpus − 1 down to 0),
/// or, when every one is claimed, the last CPU, shared, with a warning. A configured CPU that
/// another loop holds is used all the same, with a warning naming the holder. One CPU: no pinning.
/// `claim` is try_claim by default (a parameter for tests).
LoopCpuChoice choose_loop_cpu(
    std::optional<int> configured, int cpus,
    const std::function<std::optional<LoopCpuClaim>(int, pid_t*)>& claim = LoopCpuClaim::try_claim);

}  // namespace haptic::runtime
