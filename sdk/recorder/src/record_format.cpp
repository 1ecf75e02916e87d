#include "record_format.hpp"

#include <array>
#include <limits>

namespace haptic::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Cell i64(std::int64_t v) { Cell c; c.i64 = v; return c; }
Cell u64(std::uint64_t v) { Cell c; c.u64 = v; return c; }
Cell u32(std::uint32_t v) { Cell c; c.u32 = v; return c; }
Cell f64(double v) { Cell c; c.f64 = v; return c; }

using T = ColumnType;
// Absent orientation and torque (a device that measures none) are NaN; an absent kernel stamp -1.
constexpr std::array kSampleColumns = {
    SampleColumn{"received_ns", "ns", T::kInt64, [](const State& s) { return i64(steady_ns(s.received_at)); }},
    SampleColumn{"arrived_ns", "ns", T::kInt64,
                 [](const State& s) { return i64(s.arrived_at ? steady_ns(*s.arrived_at) : -1); }},
    SampleColumn{"tick", "", T::kUInt64, [](const State& s) { return u64(s.tick); }},
    SampleColumn{"sequence", "", T::kUInt64, [](const State& s) { return u64(s.sequence); }},
    SampleColumn{"server_time_s", "s", T::kDouble, [](const State& s) { return f64(s.server_time); }},
    SampleColumn{"position_x_m", "m", T::kDouble, [](const State& s) { return f64(s.position.x); }},
    SampleColumn{"position_y_m", "m", T::kDouble, [](const State& s) { return f64(s.position.y); }},
    SampleColumn{"position_z_m", "m", T::kDouble, [](const State& s) { return f64(s.position.z); }},
    SampleColumn{"velocity_x_m_s", "m/s", T::kDouble, [](const State& s) { return f64(s.velocity.x); }},
    SampleColumn{"velocity_y_m_s", "m/s", T::kDouble, [](const State& s) { return f64(s.velocity.y); }},
    SampleColumn{"velocity_z_m_s", "m/s", T::kDouble, [](const State& s) { return f64(s.velocity.z); }},
    SampleColumn{"force_x_N", "N", T::kDouble, [](const State& s) { return f64(s.force.x); }},
    SampleColumn{"force_y_N", "N", T::kDouble, [](const State& s) { return f64(s.force.y); }},
    SampleColumn{"force_z_N", "N", T::kDouble, [](const State& s) { return f64(s.force.z); }},
    SampleColumn{"proxy_x_m", "m", T::kDouble, [](const State& s) { return f64(s.proxy.x); }},
    SampleColumn{"proxy_y_m", "m", T::kDouble, [](const State& s) { return f64(s.proxy.y); }},
    SampleColumn{"proxy_z_m", "m", T::kDouble, [](const State& s) { return f64(s.proxy.z); }},
    SampleColumn{"contact_count", "", T::kUInt32, [](const State& s) { return u32(s.contact_count); }},
    SampleColumn{"flags", "", T::kUInt32, [](const State& s) { return u32(s.flags); }},
    SampleColumn{"buttons", "", T::kUInt32, [](const State& s) { return u32(s.buttons); }},
    SampleColumn{"orientation_w", "1", T::kDouble,
                 [](const State& s) { return f64(s.orientation ? s.orientation->w : kNaN); }},
    SampleColumn{"orientation_x", "1", T::kDouble,
                 [](const State& s) { return f64(s.orientation ? s.orientation->x : kNaN); }},
    SampleColumn{"orientation_y", "1", T::kDouble,
                 [](const State& s) { return f64(s.orientation ? s.orientation->y : kNaN); }},
    SampleColumn{"orientation_z", "1", T::kDouble,
                 [](const State& s) { return f64(s.orientation ? s.orientation->z : kNaN); }},
    SampleColumn{"torque_x_Nm", "N*m", T::kDouble, [](const State& s) { return f64(s.torque ? s.torque->x : kNaN); }},
    SampleColumn{"torque_y_Nm", "N*m", T::kDouble, [](const State& s) { return f64(s.torque ? s.torque->y : kNaN); }},
    SampleColumn{"torque_z_Nm", "N*m", T::kDouble, [](const State& s) { return f64(s.torque ? s.torque->z : kNaN); }},
    SampleColumn{"age_ns", "ns", T::kInt64, [](const State& s) { return i64(s.age.count()); }},
};

constexpr std::array<const char*, 9> kEventNames = {
    "unknown",       "session_opened", "session_closed", "lease_expired", "scene_changed",
    "force_fault",   "watch_started",  "device_fault",   "reset"};
constexpr std::array<const char*, 4> kConnectionNames = {"connection_connected", "connection_lost",
                                                          "connection_resumed", "connection_ended"};

}  // namespace

std::span<const SampleColumn> sample_columns() { return kSampleColumns; }

std::int64_t steady_ns(std::chrono::steady_clock::time_point at) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(at.time_since_epoch()).count();
}

EventRecord event_record(const Event& event, std::int64_t received_ns) {
  return {received_ns, static_cast<std::int32_t>(event.kind), event.session_id, event.server_time,
          event.item_id, event.message};
}

EventRecord event_record(const ConnectionChange& change, std::int64_t received_ns) {
  return {received_ns, kConnectionKindBase + static_cast<std::int32_t>(change.state), change.session_id,
          kNaN, 0, change.reason};
}

const char* event_kind_name(std::int32_t kind) {
  if (kind >= 0 && kind < static_cast<std::int32_t>(kEventNames.size())) return kEventNames[kind];
  const std::int32_t connection = kind - kConnectionKindBase;
  if (connection >= 0 && connection < static_cast<std::int32_t>(kConnectionNames.size())) {
    return kConnectionNames[connection];
  }
  return "unknown";
}

}  // namespace haptic::detail
