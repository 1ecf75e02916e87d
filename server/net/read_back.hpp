#pragma once
// What the control plane (Step, GetScene, GetObjectStates) and the viewer read back, as messages:
// one translation for both.

#include <vector>

#include "haptic/v1/service.pb.h"
#include "haptic/wire/datagram.hpp"
#include "net/scene_store.hpp"
#include "runtime/tick_sample.hpp"

namespace haptic::net {

/// A tick's sample: p_WT, v_WT, F_T_W, p_WP, contacts, flags, buttons, and R_WT and tau_T_W for a
/// device that measures the orientation.
v1::ToolState to_tool_state(const runtime::TickSample& sample);

/// A tick's sample as the State datagram's payload (the UDP stream's and the WebSocket's).
wire::StatePayload state_payload(const runtime::TickSample& sample);

/// Items as SceneStore::read gives them, with their ids and owners alongside.
v1::SceneContents to_scene_contents(const std::vector<SceneEntry>& entries);

/// The virtual masses as SceneStore::motions gives them.
v1::ObjectStates to_object_states(const std::vector<engine::ObjectMotion>& motions);

}  // namespace haptic::net
