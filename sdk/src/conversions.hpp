#pragma once
// SDK value types <-> haptic.v1 messages.

#include <vector>

#include "haptic/client.hpp"
#include "haptic/types.hpp"
#include "haptic/v1/device.pb.h"
#include "haptic/v1/scene.pb.h"
#include "haptic/v1/service.pb.h"

namespace haptic::detail {

v1::Vec3 to_proto(const Vec3& v);
Vec3 from_proto(const v1::Vec3& v);
v1::Quaternion to_proto(const Quaternion& q);
/// The message's values as they are; where an unset message means identity, check has_…() first.
Quaternion from_proto(const v1::Quaternion& q);
v1::Object to_proto(const WallSpec& wall);
v1::Object to_proto(const SphereSpec& sphere);
v1::Field to_proto(const SpringFieldSpec& spring);
v1::Object to_proto(const BoxSpec& box);
v1::Object to_proto(const CapsuleSpec& capsule);
v1::Object to_proto(const MeshSpec& mesh);
v1::Object to_proto(const TangentPlaneSpec& plane);
v1::Field to_proto(const DistanceSpringSpec& spring);
v1::Field to_proto(const PotentialFieldSpec& field);
v1::Field to_proto(const LinearFieldSpec& field);
v1::Field to_proto(const ViscousFieldSpec& field);
v1::Field to_proto(const DetentFieldSpec& field);
v1::Field to_proto(const OrientationSpringSpec& field);
v1::Field to_proto(const OrientationDetentSpec& field);
v1::OperatorInput to_proto(const OperatorInput& input);
/// The inverses, for reading a scene back (GetScene): an object or field the server holds as the
/// SDK spec that would make it. A wall's or a sphere's pose orientation is folded into its
/// normal (walls) or dropped (spheres, where it changes nothing); a potential field's
/// difference_step has no SDK counterpart (the server's default is used).
SceneSpec::Object from_proto(const v1::Object& object);
SceneSpec::Field from_proto(const v1::Field& field);
DeviceInfo from_proto(const v1::DeviceInfo& info);
Stats from_proto(const v1::Stats& stats);
StabilityReport from_proto(const v1::StabilityReport& report);
/// One StabilityReport per object of an ApplyScene reply, in order.
std::vector<StabilityReport> stability_reports(const v1::ApplySceneResponse& reply);

/// An object or field in its wire form, for Client's private registration helpers (the public
/// header only forward-declares these, so protobuf stays out of it).
struct WireObject {
  v1::Object message;
};
struct WireField {
  v1::Field message;
};
struct WireScene {
  v1::Scene message;
};
/// A sample from a Step reply (sequence 0: it came by no datagram; received_at: now).
State from_proto(const v1::ToolState& state);
Event from_proto(const v1::Event& event);
SessionSummary from_proto(const v1::SessionSummary& session);

}  // namespace haptic::detail
