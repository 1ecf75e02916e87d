#include "runtime/excitation_stage.hpp"

#include <cmath>
#include <utility>

namespace haptic::runtime {

ExcitationStage::ExcitationStage(engine::Multisine signal, engine::Vec3 axis_W, ExcitationLimits limits,
                                 ExcitationCentering centering)
    : signal_(std::move(signal)), axis_(axis_W), limits_(limits), centering_(centering) {}

engine::Vec3 ExcitationStage::force(const ToolReading& reading, std::uint64_t tick) {
  if (stop_ != Stop::kNone || tick == 0) return {};
  const engine::Vec3& p = reading.p_WT;
  if (!started_) {
    start_ = p;
    started_ = true;
  }
  const double w = limits_.box_half_width_m;
  const bool inside = std::abs(p.x - start_.x) <= w && std::abs(p.y - start_.y) <= w && std::abs(p.z - start_.z) <= w;
  const double speed = engine::norm(reading.v_WT);
  if (!inside || !(speed <= limits_.max_speed_m_s)) {
    stop_ = inside ? Stop::kTooFast : Stop::kLeftTheBox;
    stop_tick_ = tick;
    stop_position_ = p;
    stop_speed_ = speed;
    return {};
  }
  const double centering = -centering_.stiffness * engine::dot(p - start_, axis_) -
                           centering_.damping * engine::dot(reading.v_WT, axis_);
  return (signal_.force_at_tick(static_cast<std::size_t>(tick - 1)) + centering) * axis_;
}

}  // namespace haptic::runtime
