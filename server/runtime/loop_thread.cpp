#include "runtime/loop_thread.hpp"

#include <chrono>
#include <cmath>
#include <future>

namespace haptic::runtime {

LoopThread::LoopThread(TickRunner& runner, LoopCounters& counters, LatenessHistogram& lateness,
                       const LoopConfig& config)
    : runner_(runner),
      counters_(counters),
      lateness_(lateness),
      config_(config),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / config.rate_hz))) {}

LoopThread::~LoopThread() { stop(); }

RealtimeSetup LoopThread::start() {
  std::promise<RealtimeSetup> setup_promise;
  auto setup_future = setup_promise.get_future();
  start_ns_ = monotonic_now_ns();
  thread_ = std::thread([this, &setup_promise] {
    if (config_.mode == TimeMode::kLockstep) {
      setup_promise.set_value(RealtimeSetup{});
      run_lockstep();
      return;
    }
    RealtimeSetup setup = config_.use_fifo ? apply_realtime(config_.fifo_priority) : RealtimeSetup{};
    if (config_.cpu >= 0) {
      setup.cpu_error = pin_to_cpu(config_.cpu);
      if (setup.cpu_error.empty()) setup.cpu = config_.cpu;
    }
    setup_promise.set_value(setup);
    if (config_.servo != nullptr) {
      run_device_clocked();
    } else {
      run_real_time();
    }
  });
  return setup_future.get();
}

std::int64_t LoopThread::server_time_ns() const {
  if (config_.mode == TimeMode::kLockstep) {
    return static_cast<std::int64_t>(completed_ticks()) * period_ns_;
  }
  return monotonic_now_ns() - start_ns_;
}

void LoopThread::run_real_time() {
  std::int64_t deadline = monotonic_now_ns() + period_ns_;
  std::uint64_t tick = 0;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    const std::int64_t woke = sleep_then_spin_until(deadline, config_.spin_ns);
    ++tick;
    runner_.run(tick, deadline - start_ns_);
    completed_.store(tick, std::memory_order_release);
    // After the tick, so that every lateness sample belongs to a counted tick (Stats never shows
    // more samples than ticks).
    lateness_.record(woke - deadline, woke);
    deadline += period_ns_;
    const std::int64_t now = monotonic_now_ns();
    if (now > deadline) {
      // The tick (or the host) overran: skip the periods already gone rather than burst.
      const std::int64_t missed = (now - deadline) / period_ns_ + 1;
      counters_.overruns.fetch_add(static_cast<std::uint64_t>(missed), std::memory_order_relaxed);
      deadline += missed * period_ns_;
    }
  }
}

void LoopThread::run_device_clocked() {
  struct Context {
    LoopThread* loop;
    std::uint64_t tick = 0;
  } context{this};
  const bool ended_well = config_.servo->run(
      [](void* self, std::int64_t monotonic_ns) {
        auto& c = *static_cast<Context*>(self);
        LoopThread& loop = *c.loop;
        if (loop.stop_requested_.load(std::memory_order_acquire)) return true;
        ++c.tick;
        loop.runner_.run(c.tick, monotonic_ns - loop.start_ns_);
        loop.completed_.store(c.tick, std::memory_order_release);
        return false;
      },
      &context);
  if (!ended_well || !stop_requested_.load(std::memory_order_acquire)) {
    servo_failed_.store(true, std::memory_order_release);
  }
}

void LoopThread::run_lockstep() {
  std::uint64_t tick = 0;
  for (;;) {
    const std::uint64_t target = target_.load(std::memory_order_acquire);
    if (stop_requested_.load(std::memory_order_acquire)) return;
    if (restart_requested_.load(std::memory_order_acquire)) {
      // A reset (its caller holds step_mutex_ and waits for this): ticks count from 1 again.
      tick = 0;
      completed_.store(0, std::memory_order_release);
      target_.store(0, std::memory_order_release);
      restart_requested_.store(false, std::memory_order_release);
      step_signal_.fetch_add(1, std::memory_order_release);
      step_signal_.notify_all();
      continue;
    }
    if (tick >= target) {
      target_.wait(target, std::memory_order_acquire);
      continue;
    }
    while (tick < target) {
      ++tick;
      runner_.run(tick, static_cast<std::int64_t>(tick - 1) * period_ns_);
      completed_.store(tick, std::memory_order_release);
    }
    step_signal_.fetch_add(1, std::memory_order_release);
    step_signal_.notify_all();
  }
}

LoopThread::Stepped LoopThread::step(std::uint32_t ticks) {
  std::lock_guard lock(step_mutex_);
  const std::uint64_t target = completed_ticks() + ticks;
  target_.store(target, std::memory_order_release);
  target_.notify_all();
  for (;;) {
    const std::uint32_t seen = step_signal_.load(std::memory_order_acquire);
    if (completed_ticks() >= target || stop_requested_.load(std::memory_order_acquire)) break;
    step_signal_.wait(seen, std::memory_order_acquire);
  }
  return {completed_ticks(), run_.load(std::memory_order_acquire)};
}

bool LoopThread::reset_lockstep(const std::function<bool(const std::function<void()>&)>& while_idle) {
  std::lock_guard lock(step_mutex_);
  // No step is in progress (we hold its mutex): the loop thread runs no tick until one raises the
  // target. `restart` has the loop thread itself number its ticks from 1 again, and waits for it.
  const auto restart = [this] {
    restart_requested_.store(true, std::memory_order_release);
    target_.store(kRestartTarget, std::memory_order_release);  // wakes it (a value it cannot hold)
    target_.notify_all();
    for (;;) {
      const std::uint32_t seen = step_signal_.load(std::memory_order_acquire);
      if (!restart_requested_.load(std::memory_order_acquire) || stop_requested_.load(std::memory_order_acquire)) {
        break;
      }
      step_signal_.wait(seen, std::memory_order_acquire);
    }
    run_.fetch_add(1, std::memory_order_acq_rel);
  };
  return while_idle(restart);
}

void LoopThread::ramp_out_and_stop() {
  if (thread_.joinable()) {
    runner_.begin_output_ramp(completed_ticks() + 1);
    if (config_.mode == TimeMode::kLockstep) {
      (void)step(static_cast<std::uint32_t>(runner_.config().output_ramp_ticks + 1));
    } else {
      // Bounded wait: at 100 Hz a 50-tick ramp takes 0.5 s; stalls of the host add a little.
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
      while (!runner_.output_ramp_done() && std::chrono::steady_clock::now() < give_up) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
  }
  stop();
}

void LoopThread::stop() {
  stop_requested_.store(true, std::memory_order_release);
  target_.fetch_add(1, std::memory_order_acq_rel);
  target_.notify_all();
  if (thread_.joinable()) thread_.join();
  step_signal_.fetch_add(1, std::memory_order_release);  // releases any step() still waiting
  step_signal_.notify_all();
}

}  // namespace haptic::runtime
