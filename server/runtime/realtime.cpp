#include "runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace haptic::runtime {

namespace {

/// How much of its stack the loop thread touches before its first tick. Unit: bytes.
constexpr std::size_t kLoopStackPrefault = 256 * 1024;

// Touches the stack pages the loop will use, so that (with MCL_ONFAULT) they are faulted in and
// locked now, not on a tick. Not inlined: the frame must be this function's own.
[[gnu::noinline]] void prefault_stack() {
  volatile std::uint8_t frame[kLoopStackPrefault];
  for (std::size_t i = 0; i < sizeof(frame); i += 4096) frame[i] = 0;
}

}  // namespace

RealtimeSetup apply_realtime(int priority) {
  RealtimeSetup setup;
  sched_param param{};
  param.sched_priority = priority;
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc == 0) {
    setup.fifo = true;
  } else {
    setup.fifo_error = std::strerror(rc);
  }
  // MCL_ONFAULT: lock pages as they are touched, not whole mappings. Without it every later
  // mapping — every control-plane thread's 8 MB stack — is locked and made resident in full when
  // created (2,000 event streams once took 16 GB); with it a thread costs only the pages it uses,
  // and the loop's own memory is locked all the same, since the loop has touched it (its stack
  // below, its scene and rings when they were built).
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0) {
    prefault_stack();
    setup.memory_locked = true;
  } else {
    setup.mlock_error = std::strerror(errno);
  }
  return setup;
}

std::string set_fifo_priority(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc != 0) {
    return std::strerror(rc);
  }
  return {};
}

std::string pin_to_cpu(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set); rc != 0) {
    return std::strerror(rc);
  }
  return {};
}

std::int64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::int64_t sleep_then_spin_until(std::int64_t deadline_ns, std::int64_t spin_ns) {
  const std::int64_t wake_ns = deadline_ns - spin_ns;
  if (monotonic_now_ns() < wake_ns) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake_ns / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(wake_ns % 1'000'000'000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
  std::int64_t now = monotonic_now_ns();
  while (now < deadline_ns) now = monotonic_now_ns();
  return now;
}

}  // namespace haptic::runtime
