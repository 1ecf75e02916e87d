#include "net/read_back.hpp"

#include "schema/scene_specs.hpp"

namespace haptic::net {

v1::ToolState to_tool_state(const runtime::TickSample& sample) {
  v1::ToolState state;
  state.set_tick(sample.tick);
  state.set_server_time_s(static_cast<double>(sample.time_ns) * 1e-9);
  *state.mutable_position() = schema::to_proto(sample.p_WT);
  *state.mutable_velocity() = schema::to_proto(sample.v_WT);
  *state.mutable_force() = schema::to_proto(sample.F_T_W);
  *state.mutable_proxy() = schema::to_proto(sample.p_WP);
  state.set_contact_count(sample.contact_count);
  state.set_flags(sample.flags);
  state.set_buttons(sample.buttons);
  if (sample.has_orientation) {  // as the datagram: orientation and torque, or neither
    *state.mutable_orientation() = schema::to_proto(sample.R_WT);
    *state.mutable_torque() = schema::to_proto(sample.tau_T_W);
  }
  return state;
}

v1::SceneContents to_scene_contents(const std::vector<SceneEntry>& entries) {
  v1::SceneContents contents;
  for (const SceneEntry& entry : entries) {
    if (entry.source.object) {
      *contents.mutable_scene()->add_objects() = *entry.source.object;
      contents.add_object_ids(entry.id);
      contents.add_object_sessions(entry.session_id);
    } else if (entry.source.field) {
      *contents.mutable_scene()->add_fields() = *entry.source.field;
      contents.add_field_ids(entry.id);
      contents.add_field_sessions(entry.session_id);
    }
  }
  return contents;
}

v1::ObjectStates to_object_states(const std::vector<engine::ObjectMotion>& motions) {
  v1::ObjectStates states;
  for (const engine::ObjectMotion& motion : motions) {
    v1::ObjectState& out = *states.add_objects();
    out.set_id(motion.id);
    *out.mutable_position() = schema::to_proto(motion.p_WO);
    *out.mutable_velocity() = schema::to_proto(motion.v_WO);
  }
  return states;
}

wire::StatePayload state_payload(const runtime::TickSample& sample) {
  wire::StatePayload state;
  state.tick = sample.tick;
  state.p_WT = {sample.p_WT.x, sample.p_WT.y, sample.p_WT.z};
  state.v_WT = {sample.v_WT.x, sample.v_WT.y, sample.v_WT.z};
  state.F_T_W = {sample.F_T_W.x, sample.F_T_W.y, sample.F_T_W.z};
  state.p_WP = {sample.p_WP.x, sample.p_WP.y, sample.p_WP.z};
  state.contact_count = sample.contact_count;
  state.flags = sample.flags;
  state.buttons = sample.buttons;
  state.has_orientation = sample.has_orientation;  // only then R_WT and tau_T_W go out
  state.R_WT = {sample.R_WT.w, sample.R_WT.x, sample.R_WT.y, sample.R_WT.z};
  state.tau_T_W = {sample.tau_T_W.x, sample.tau_T_W.y, sample.tau_T_W.z};
  return state;
}

}  // namespace haptic::net
