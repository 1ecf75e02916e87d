#pragma once
// The simulated operator's input as a simulated device holds it: set off the loop through a
// lock-free mailbox, read on the loop together with the time since it arrived (profiles and
// trajectories start from the tick the input reaches the loop, so lockstep stays reproducible).

#include <cstdint>

#include "engine/operator/simulated_hand.hpp"
#include "runtime/latest_value.hpp"

namespace haptic::runtime {

class SimulatedOperator {
 public:
  /// Off the loop.
  void set(const engine::HandInput& input) { input_.store(input); }

  /// On the loop, at the start of a tick: the input, and in `t_s` the time since it arrived.
  /// The input (up to a few kB with a recorded force) is copied only when a new one has arrived;
  /// the reference stays valid until the next begin_tick().
  const engine::HandInput& begin_tick(double& t_s) {
    if (const std::uint64_t version = input_.version(); version != version_) {
      current_ = input_.load();
      version_ = input_.version() == version ? version : 0;  // a store raced the load: reload next tick
      time_s_ = 0.0;
    }
    t_s = time_s_;
    return current_;
  }

  /// On the loop, after the plant has advanced by dt. Unit: s.
  void end_tick(double dt) { time_s_ += dt; }

 private:
  LatestValue<engine::HandInput> input_;
  engine::HandInput current_;  // loop only: the input in force
  std::uint64_t version_ = 0;  // loop only: the version of current_
  double time_s_ = 0.0;        // loop only. Unit: s.
};

}  // namespace haptic::runtime
