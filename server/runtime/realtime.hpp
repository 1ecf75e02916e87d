#pragma once
// Real-time scheduling and pacing on Linux: SCHED_FIFO, locked memory, absolute-deadline sleeps.

#include <cstdint>
#include <string>

namespace haptic::runtime {

struct RealtimeSetup {
  bool fifo = false;            // SCHED_FIFO granted to the calling thread
  bool memory_locked = false;   // mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) succeeded
  std::string fifo_error;       // why not, when not
  std::string mlock_error;
  int cpu = -1;                 // the CPU the loop is pinned to, -1 if none
  std::string cpu_error;
};

/// Asks for SCHED_FIFO at `priority` for the calling thread and locks memory. Never fails hard:
/// what was refused is reported so the caller can log it (off the loop) and carry on.
RealtimeSetup apply_realtime(int priority);

/// Asks for SCHED_FIFO at `priority` for the calling thread alone (no memory locking). Empty on
/// success, else why not.
std::string set_fifo_priority(int priority);

/// Pins the calling thread to one CPU. Empty on success, else why not.
std::string pin_to_cpu(int cpu);

/// CLOCK_MONOTONIC now. Unit: ns.
std::int64_t monotonic_now_ns();

/// Sleeps with an absolute CLOCK_MONOTONIC deadline until `spin_ns` before `deadline_ns`, then
/// spins until the deadline (measured on these machines: p99 lateness ≈ 30–60 µs this way against
/// ≈ 160–200 µs for sleep alone). Returns the time of return. Unit: ns.
std::int64_t sleep_then_spin_until(std::int64_t deadline_ns, std::int64_t spin_ns);

}  // namespace haptic::runtime
