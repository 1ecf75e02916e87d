#pragma once
// The loop thread: the only caller of TickRunner::run, and so the only writer of device commands.
//
// Real time: absolute CLOCK_MONOTONIC deadlines, sleep then spin, SCHED_FIFO + mlockall when
// permitted; a tick that ends past the next deadline counts the missed periods as overruns and
// skips them (never a burst of catch-up ticks). Lockstep: ticks run only when step() asks, as fast
// as possible, and server time is tick × period, so every run is exactly reproducible.
// Device-clocked (real time with a ServoClock): the loop thread hands itself to the device's servo
// loop, which runs one tick per servo cycle; server time is the cycle's time since start.

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

#include "runtime/loop_stats.hpp"
#include "runtime/realtime.hpp"
#include "runtime/servo_clock.hpp"
#include "runtime/tick_runner.hpp"

namespace haptic::runtime {

enum class TimeMode { kRealTime, kLockstep };

struct LoopConfig {
  double rate_hz = 1000.0;     // Unit: Hz. 100 ... 10000.
  TimeMode mode = TimeMode::kRealTime;
  bool use_fifo = true;
  int fifo_priority = 80;
  std::int64_t spin_ns = 100'000;  // Unit: ns.
  int cpu = -1;                    // Pin the loop to this CPU; -1: no pinning.
  /// Real time only: the device whose servo loop paces the ticks (rate_hz must be its rate);
  /// nullptr: the loop's own clock. Not owned.
  ServoClock* servo = nullptr;
};

class LoopThread {
 public:
  LoopThread(TickRunner& runner, LoopCounters& counters, LatenessHistogram& lateness,
             const LoopConfig& config);
  ~LoopThread();
  LoopThread(const LoopThread&) = delete;
  LoopThread& operator=(const LoopThread&) = delete;

  /// Starts the thread; returns what real-time setup it got (real-time mode only).
  RealtimeSetup start();

  /// What a lockstep step reached: the index of its last tick, and the run it belongs to (resets
  /// so far), read together.
  struct Stepped {
    std::uint64_t tick = 0;
    std::uint64_t run = 0;
  };
  /// Lockstep only: runs `ticks` ticks. Callers from several threads are served one after another.
  Stepped step(std::uint32_t ticks);

  /// Lockstep only, off the loop: waits out any step in progress, then calls `while_idle` while
  /// no tick runs (steps wait meanwhile), handing it `restart`, which has the loop number its ticks
  /// from 1 again (server time 0) and starts the next run. `while_idle` puts the devices and the
  /// scene back around it; returns what it returns.
  bool reset_lockstep(const std::function<bool(const std::function<void()>& restart)>& while_idle);
  /// Resets so far (each starts a run whose ticks count from 1).
  std::uint64_t run() const { return run_.load(std::memory_order_acquire); }

  /// Ramps the output force to zero over the runner's output_ramp_ticks and waits for it (in
  /// lockstep the ramp is run as ticks), then stops the thread.
  void ramp_out_and_stop();

  /// Stops the thread at once (joins).
  void stop();

  /// Ticks completed so far.
  std::uint64_t completed_ticks() const { return completed_.load(std::memory_order_acquire); }
  /// Server time now. Unit: ns. Lockstep: completed ticks × period.
  std::int64_t server_time_ns() const;
  std::int64_t period_ns() const { return period_ns_; }
  /// CLOCK_MONOTONIC time of server time 0 (real time only; set by start()). Unit: ns.
  std::int64_t start_ns() const { return start_ns_; }
  const LoopConfig& config() const { return config_; }
  /// Device-clocked: the device's servo loop ended on its own or could not run (no more ticks).
  bool servo_failed() const { return servo_failed_.load(std::memory_order_acquire); }

 private:
  void run_real_time();
  void run_lockstep();
  void run_device_clocked();

  TickRunner& runner_;
  LoopCounters& counters_;
  LatenessHistogram& lateness_;
  LoopConfig config_;
  std::int64_t period_ns_;
  std::int64_t start_ns_ = 0;

  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> servo_failed_{false};
  std::atomic<std::uint64_t> completed_{0};
  std::atomic<std::uint64_t> target_{0};  // lockstep: run until this tick
  // Lockstep: bumped after each batch of ticks and by stop(), so a waiting step() always wakes
  // (a 32-bit word: libstdc++ waits on it with a plain futex).
  std::atomic<std::uint32_t> step_signal_{0};
  std::mutex step_mutex_;                 // serialises step() callers (off the loop)
  std::atomic<std::uint64_t> run_{0};     // resets so far
  std::atomic<bool> restart_requested_{false};  // lockstep: reset_lockstep asks the loop thread
  static constexpr std::uint64_t kRestartTarget = UINT64_MAX;
};

}  // namespace haptic::runtime
