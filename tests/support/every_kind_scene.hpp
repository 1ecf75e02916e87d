#pragma once
// One object of every shape and one field of every kind, registered through the SDK around the
// point-mass device's workspace (±0.1 m), clear of the tool's start at z = 20 mm: what the viewer's
// tests draw and read back.

#include <haptic/haptic.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace haptic::test {

/// What was registered, in registration order (ids ascend with it).
struct EveryKind {
  std::vector<ObjectHandle> objects;
  std::vector<FieldHandle> fields;
  /// Each object's shape and each field's kind, as the oneof's case is named in haptic.v1
  /// ("half_space", "sphere", ...; "spring_to_point", "spring", ...).
  std::vector<std::string> object_kinds;
  std::vector<std::string> field_kinds;
  std::size_t pushable_sphere = 0;  ///< index in `objects` of the sphere with dynamics
};

inline EveryKind register_every_kind(Client& client) {
  EveryKind out;
  const Impedance firm{.stiffness = 500.0, .damping = 1.0};
  const auto object = [&](ObjectHandle handle, const char* kind) {
    out.objects.push_back(std::move(handle));
    out.object_kinds.emplace_back(kind);
  };
  const auto field = [&](FieldHandle handle, const char* kind) {
    out.fields.push_back(std::move(handle));
    out.field_kinds.emplace_back(kind);
  };
  object(client.add_wall({.point = {0, 0, -0.06}, .normal = {0, 0, 1}, .impedance = firm}), "half_space");
  out.pushable_sphere = out.objects.size();
  object(client.add_sphere({.center = {0.05, 0.0, 0.0},
                            .radius = 0.015,
                            .impedance = firm,
                            .dynamics = {.mass = 0.5, .damping = 1.0}}),
         "sphere");
  object(client.add_box(
             {.pose = {.position = {-0.05, 0.0, 0.0},
                       .orientation = {std::cos(std::numbers::pi / 8), 0, 0, std::sin(std::numbers::pi / 8)}},
              .half_extents = {0.015, 0.01, 0.008},
              .impedance = firm}),
         "box");
  object(client.add_capsule(
             {.pose = {.position = {0.0, 0.05, 0.0}, .orientation = {std::sqrt(0.5), std::sqrt(0.5), 0, 0}},
              .radius = 0.008,
              .half_length = 0.015,
              .impedance = firm}),
         "capsule");
  // A tetrahedron, its faces counter-clockwise seen from outside.
  object(client.add_mesh({.pose = {.position = {0.0, -0.06, -0.01}},
                          .vertices = {{0, 0, 0}, {0.025, 0, 0}, {0, 0.025, 0}, {0, 0, 0.025}},
                          .indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3},
                          .impedance = firm}),
         "mesh");
  object(client.add_tangent_plane({.pose = {.position = {-0.06, 0.06, -0.03}},
                                   .normal = {0, 0, 1},
                                   .tangential_stiffness = 100.0,
                                   .impedance = firm}),
         "tangent_plane");
  field(client.add_spring_field({.anchor = {0.0, 0.0, 0.05}, .stiffness = 5.0}), "spring_to_point");
  field(client.add_field(DistanceSpringSpec{
            .anchor = {.kind = Distance::Kind::kLine, .origin = {0.06, 0.06, 0}, .axis = {0, 0, 1}},
            .stiffness = 2.0}),
        "spring");
  field(client.add_field(
            PotentialFieldSpec{.distance = {.kind = Distance::Kind::kPoint, .origin = {-0.06, -0.06, 0.04}},
                               .order = 2,
                               .gain = 1.0,
                               .offset = 0.02}),
        "potential");
  field(client.add_field(LinearFieldSpec{
            .origin = {0.06, -0.06, 0.04}, .force = {0, 0, 0.5}, .radius = 0.02, .fade_width = 0.01}),
        "linear");
  field(client.add_field(ViscousFieldSpec{
            .damping = 0.5, .center = {-0.06, 0.0, 0.06}, .radius = 0.02, .fade_width = 0.005}),
        "viscous");
  field(client.add_field(
            DetentFieldSpec{.distance = {.kind = Distance::Kind::kPoint, .origin = {0.0, -0.03, 0.06}},
                            .depth = 0.005,
                            .radius = 0.01,
                            .rim_height = 0.001,
                            .rim_width = 0.004}),
        "detent");
  return out;
}

}  // namespace haptic::test
