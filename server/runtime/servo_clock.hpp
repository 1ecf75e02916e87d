#pragma once
// Device-clocked mode: a device whose own servo loop (a vendor runtime) paces the ticks. The loop
// thread hands itself to run(), which calls `tick` once per servo cycle until it returns true.

#include <cstdint>

namespace haptic::runtime {

class ServoClock {
 public:
  /// One tick at the cycle's CLOCK_MONOTONIC time (ns); returns true when run() should return.
  using Tick = bool (*)(void* context, std::int64_t monotonic_ns);

  virtual ~ServoClock() = default;
  /// The servo loop's rate. Unit: Hz.
  virtual double rate_hz() const = 0;
  /// Runs the servo loop on the calling thread; false if it could not run or ended on its own.
  virtual bool run(Tick tick, void* context) = 0;
};

}  // namespace haptic::runtime
