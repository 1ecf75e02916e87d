#pragma once

#include <cstdint>

#include "engine/core/vec3.hpp"

namespace haptic::runtime {

/// Everything the loop publishes about one tick. Frames: W world, T tool, P proxy.
struct TickSample {
  std::uint64_t tick = 0;       // Tick index, from 1.
  std::int64_t time_ns = 0;     // Server time of the tick's start: tick * period in lockstep.
  engine::Vec3 p_WT;            // Unit: m.
  engine::Vec3 v_WT;            // Unit: m/s.
  engine::Vec3 F_T_W;           // Commanded force after the safety stage. Unit: N.
  engine::Vec3 tau_T_W;         // Commanded torque after the safety stage (devices that take
                                // torques and scenes with orientation fields), else 0. Unit: N·m.
  engine::Vec3 p_WP;            // Proxy point. Unit: m.
  engine::Quat R_WT;            // Tool orientation (devices that measure one), else identity.
  engine::Vec3 w_WT;            // Its angular velocity in W (such devices), else 0. Unit: rad/s.
  bool has_orientation = false; // The port's device measures the orientation.
  std::uint32_t contact_count = 0;
  std::uint32_t flags = 0;      // haptic::wire::StateFlags bits.
  std::uint32_t buttons = 0;    // The device's buttons, bit i for button i.
};

}  // namespace haptic::runtime
