#include "runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <cerrno>
#include <cstring>

namespace haptic::runtime {

RealtimeSetup apply_realtime(int priority) {
  RealtimeSetup setup;
  sched_param param{};
  param.sched_priority = priority;
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); rc == 0) {
    setup.fifo = true;
  } else {
    setup.fifo_error = std::strerror(rc);
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    setup.memory_locked = true;
  } else {
    setup.mlock_error = std::strerror(errno);
  }
  return setup;
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
