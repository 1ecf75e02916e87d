#pragma once
// Validation at the boundary: protobuf messages from clients and config files become engine specs,
// or an error that names the offending field ("object.impedance.stiffness: must be finite and
// >= 0, got nan"). Engine code downstream assumes valid input.

#include <cstddef>
#include <string>

#include "engine/operator/simulated_hand.hpp"
#include <vector>

#include "engine/scene/scene_spec.hpp"
#include "haptic/v1/device.pb.h"
#include "haptic/v1/scene.pb.h"

namespace haptic::schema {

/// Ranges accepted for scene parameters. Generous, but they keep numbers physical.
struct SceneLimits {
  double max_abs_position = 10.0;   // Unit: m.
  double max_stiffness = 1.0e6;     // Unit: N/m.
  double max_damping = 1.0e4;       // Unit: N*s/m.
  double max_radius = 10.0;         // Unit: m.
  double max_force = 1.0e4;         // Unit: N.
  std::size_t max_mesh_triangles = 20000;  // per mesh
  double max_friction = 10.0;       // μ_s, μ_d.
  double max_impedance_mass = 100.0;  // Unit: kg.
  double max_object_mass = 1000.0;    // Virtual masses. Unit: kg.
  double max_rotational_stiffness = 1.0e3;  // Orientation fields. Unit: N*m/rad.
  double max_rotational_damping = 1.0e2;    // Unit: N*m*s/rad.
  double max_torque = 1.0e3;                // Unit: N*m.
  double max_field_energy = 1.0e3;          // An orientation detent's depth and rim. Unit: J.
  double period_s = 1e-3;             // The loop period, for the sampled-stability checks. Unit: s.
  /// The device as a mass-damper at its tool point (DeviceDescription::apparent_*); 0: unknown.
  double device_mass = 0.0;     // Unit: kg.
  double device_damping = 0.0;  // Unit: N*s/m.
  /// Completes "needs a device that gives its damping (…)" when the model is missing: which
  /// device lacks it (with several ports, the least damped or the one without a model).
  std::string device_unknown_reason = "this one does not";
};

/// Each returns an empty string on success, else "<path>: <what is wrong>". A mesh is validated
/// in full and its bounding-volume hierarchy built here, off the loop.
std::string to_object_spec(const v1::Object& object, const std::string& path,
                           const SceneLimits& limits, engine::ObjectSpec& out);
std::string to_field_spec(const v1::Field& field, const std::string& path,
                          const SceneLimits& limits, engine::FieldSpec& out);
/// A whole scene's objects and fields, each converted and validated, in the scene's order.
struct SceneSpecs {
  std::vector<engine::ObjectSpec> objects;
  std::vector<engine::FieldSpec> fields;
};
/// Empty on success, else the first error, "<prefix>objects[i]…: …" (prefix: "scene.",
/// "initial_scene.", or "" for a scene file's own elements). All or nothing: `out` is written
/// only on success.
std::string to_scene_specs(const v1::Scene& scene, const std::string& prefix,
                           const SceneLimits& limits, SceneSpecs& out);
std::string to_hand_input(const v1::OperatorInput& input, const std::string& path,
                          const SceneLimits& limits, engine::HandInput& out);

engine::Vec3 to_engine(const v1::Vec3& v);
v1::Vec3 to_proto(const engine::Vec3& v);
v1::Quaternion to_proto(const engine::Quat& q);

}  // namespace haptic::schema
